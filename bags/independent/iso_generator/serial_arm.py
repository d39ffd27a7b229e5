"""A UR5 arm from its published standard DH table (Universal Robots), for the tool-offset case.

Standard DH (Denavit–Hartenberg 1955): A_i = Rz(θ_i)·Tz(d_i)·Tx(a_i)·Rx(α_i). UR5 (UR's
published parameters): d1 = 89.159 mm, a2 = −425 mm, a3 = −392.25 mm, d4 = 109.15 mm,
d5 = 94.65 mm, d6 = 82.3 mm, α1 = α4 = +90°, α5 = −90°. The tool point is an SMR on the
flange, given in the flange frame; its true position differs from the nominal by the error of
the offset vector (the bracket machined or assembled off), which turns with the wrist.
"""

import numpy as np

UR5_DH = [  # (d, a, alpha) per joint, m and rad
    (0.089159, 0.0, np.pi / 2),
    (0.0, -0.425, 0.0),
    (0.0, -0.39225, 0.0),
    (0.10915, 0.0, np.pi / 2),
    (0.09465, 0.0, -np.pi / 2),
    (0.0823, 0.0, 0.0),
]


def dh_matrix(theta, d, a, alpha):
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct],
                     [st, ct * ca, -ct * sa, a * st],
                     [0.0, sa, ca, d],
                     [0.0, 0.0, 0.0, 1.0]])


def flange_pose(joints, base_translation):
    """4×4 pose of the flange in the cell frame (base only translated: a pedestal)."""
    T = np.eye(4)
    T[:3, 3] = base_translation
    for theta, (d, a, alpha) in zip(joints, UR5_DH):
        T = T @ dh_matrix(theta, d, a, alpha)
    return T


def tool_point(joints, base_translation, tool_in_flange):
    T = flange_pose(joints, base_translation)
    return T[:3, :3] @ np.asarray(tool_in_flange) + T[:3, 3]
