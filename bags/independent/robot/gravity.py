"""Gravity in the robot's base frame, the torque it exerts about a joint, and the bending
moment it puts on a section of the column.

* The site's level frame W has z up (opposite to gravity): g_W = (0, 0, −g), g = 9.81 m/s².
  The chassis stands on ground tilted by (roll, pitch): R_WB = Rx(roll)·Ry(pitch) (rotations.py
  `tilt_matrix`), so in the base frame g_B = R_WBᵀ·g_W.
* Gravity torque about joint j (axis â_j through the point o_j, both in the base frame) of the
  links outboard of it, each a mass m_i at its centre of mass c_i:
      τ_j = â_j · Σ_i (c_i − o_j) × m_i·g_B
  — the generalised gravity force of Lagrangian mechanics, τ_j = −∂V/∂q_j with
  V = −Σ m_i g_B·c_i (any robotics text, e.g. Siciliano et al., *Robotics*, 2009, §7.2); the sign
  is the direction the torque turns the joint (a positive τ drives q_j up). Checked against a
  finite difference of V in test_physics.py.
* The bending moment on a column section at the point s of its axis (unit vector ẑ_c) is the
  moment of the weights above it, Σ_i (c_i − s) × m_i·g_B, less its torsion component along
  ẑ_c (the column is taken stiff in torsion); a weight's horizontal lever about the axis makes
  most of it, and on tilted ground the vertical lever adds (c_i − s)_vertical × m_i·g_B,horizontal.
"""

import numpy as np

from rotations import tilt_matrix

G = 9.81  # m/s²


def gravity_in_base(roll, pitch):
    """g_B (3,) for ground tilted by roll (about base x) and pitch (about base y) [rad]."""
    return tilt_matrix(roll, pitch).T @ np.array([0.0, 0.0, -G])


def weight_moment(masses, centres, point, g_base):
    """Σ_i (c_i − point) × m_i·g: (N,3). masses {link: kg}, centres {link: (N,3)}, point (N,3)."""
    M = np.zeros_like(point)
    for link, m in masses.items():
        if m > 0.0:
            M += np.cross(centres[link] - point, m * g_base[None, :])
    return M


def joint_gravity_torque(urdf, frames, joint_frames, joint, g_base):
    """τ_j (N,) about `joint` from every link outboard of it."""
    links = urdf.subtree_links(joint)
    centres = urdf.centres_of_mass(frames, links)
    masses = {l: urdf.links[l]["mass"] for l in links}
    origin = joint_frames[joint][:, :3, 3]
    axis = urdf.joint_axis_in_root(joint_frames, joint)
    return np.einsum("ni,ni->n", axis, weight_moment(masses, centres, origin, g_base))


def bending_part(moment, axis):
    """The moment less its component along the (unit, (3,)) column axis."""
    return moment - np.outer(moment @ axis, axis)
