"""The arm's joints yielding under gravity: elastic compliance and lost motion.

* Compliance: a joint's drive (motor, harmonic gear, shaft) is a torsional spring between the
  encoder's angle and the output's: under the gravity torque τ_j about it the output turns by
      Δθ_j = k_j · τ_j           [rad = rad/(N·m) · N·m]
  in the direction the torque turns it (τ_j > 0 drives q_j up: gravity.py). k_j of harmonic
  drives of a 10-kg-payload arm: 1e-6 … 2e-5 rad/(N·m), the shoulder and elbow the softest
  (they carry the most and their gears are the longest lever of the error).
* Lost motion (backlash): the gear's play b_j lets the output rest against one flank; gravity
  picks the flank, so the output sits b_j/2 from the play's middle toward the torque:
      Δθ_j = (b_j/2) · sign(τ_j)
  (the commanded angle is the middle of the play). A joint whose gravity torque changes sign
  between two waypoints jumps by b_j — which the rigid URDF cannot follow.

First order: the torques are those of the undeflected pose (the deflections are ~1 mrad; what
they change in the torques is ~0.1 % of them).
"""

import numpy as np

from gravity import joint_gravity_torque


def gravity_torques(urdf, frames, joint_frames, joints, g_base):
    return {j: joint_gravity_torque(urdf, frames, joint_frames, j, g_base) for j in joints}


def joint_deflections(torques, compliance, backlash):
    """{joint: Δθ (N,)}: compliance {joint: k [rad/(N·m)]}, backlash {joint: b [rad]}."""
    out = {}
    for j, tau in torques.items():
        d = compliance.get(j, 0.0) * tau
        if backlash.get(j, 0.0):
            d = d + 0.5 * backlash[j] * np.sign(tau)
        out[j] = d
    return out
