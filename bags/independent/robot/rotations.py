"""Rotations and homogeneous transforms, vectorised over a leading axis of waypoints.

Conventions (written out because the URDF and the instrument each have their own):
* URDF `<origin rpy="r p y">` is R = Rz(y)·Ry(p)·Rx(r) (fixed-axis roll, pitch, yaw about the
  parent's x, y, z; ROS REP 103 / the URDF specification, wiki.ros.org/urdf/XML/joint);
* a rotation vector φ (axis·angle) becomes R by Rodrigues' formula
  R = I + sin|φ|·[n]× + (1 − cos|φ|)·[n]×², n = φ/|φ|;
* a point p in frame B is T_AB·p in frame A, T_AB = [[R, t], [0, 1]].
"""

import numpy as np


def rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rpy_matrix(rpy):
    """URDF rpy: Rz(yaw)·Ry(pitch)·Rx(roll)."""
    r, p, y = rpy
    return rot_z(y) @ rot_y(p) @ rot_x(r)


def transform(R=None, t=None):
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if t is not None:
        T[:3, 3] = t
    return T


def skew(v):
    """[v]× for v (..., 3): (..., 3, 3) with [v]×·w = v × w."""
    v = np.asarray(v, dtype=float)
    z = np.zeros(v.shape[:-1])
    return np.stack([np.stack([z, -v[..., 2], v[..., 1]], -1),
                     np.stack([v[..., 2], z, -v[..., 0]], -1),
                     np.stack([-v[..., 1], v[..., 0], z], -1)], -2)


def rotvec_matrix(phi):
    """Rodrigues: rotation vectors (..., 3) → matrices (..., 3, 3) (exact for any angle)."""
    phi = np.asarray(phi, dtype=float)
    angle = np.linalg.norm(phi, axis=-1)
    safe = np.where(angle > 1e-300, angle, 1.0)
    n = phi / safe[..., None]
    K = skew(n)
    s, c = np.sin(angle)[..., None, None], np.cos(angle)[..., None, None]
    R = np.eye(3) + s * K + (1.0 - c) * (K @ K)
    return np.where((angle > 1e-300)[..., None, None], R, np.eye(3))


def axis_angle_matrices(axis, angles):
    """Rotations about one fixed unit axis (3,) by angles (N,): (N, 3, 3)."""
    return rotvec_matrix(np.asarray(angles, dtype=float)[:, None] * np.asarray(axis, dtype=float)[None, :])


def apply(T, p):
    """T (..., 4, 4) applied to points p (..., 3)."""
    return np.einsum("...ij,...j->...i", T[..., :3, :3], p) + T[..., :3, 3]


def rotation_to_rotvec(R):
    """Inverse of Rodrigues for angles < π (used for small deflections and pose reports)."""
    R = np.asarray(R, dtype=float)
    c = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arccos(c)
    v = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1)
    s = np.sin(angle)
    scale = np.where(s > 1e-12, angle / (2.0 * np.where(s > 1e-12, s, 1.0)), 0.5)
    return v * scale[..., None]


def tilt_matrix(roll, pitch):
    """A small tilt of a frame off the level: Rx(roll)·Ry(pitch) (roll about x, pitch about y)."""
    return rot_x(roll) @ rot_y(pitch)
