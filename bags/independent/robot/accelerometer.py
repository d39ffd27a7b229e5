"""A 3-axis accelerometer at rest: it reads the specific force, the reaction to gravity,
f = a − g (here a = 0): +9.81 m/s² along its z when level and upright (any MEMS/servo
accelerometer datasheet; Titterton & Weston, *Strapdown Inertial Navigation*, ch. 4), expressed
in its own (sensor) frame:
    reading = R_SBᵀ·(−g_B) + bias + noise,
R_SB the sensor frame's orientation in the robot's base frame — the URDF frame of the link it is
fixed to (true: deflected with the column for the tip sensor) times a mounting misalignment
(1–5 mrad, the board not square in its housing), bias 0.01–0.05 m/s² per axis (a bias b
perpendicular to gravity reads as a tilt of b/g: 1–5 mrad), noise σ 0.005 m/s² per axis and
logged reading.
"""

import numpy as np

from rotations import rotvec_matrix


def readings(sensor_rotation_in_base, g_base, truth, rng):
    """(N,3) readings [m/s²]: sensor_rotation_in_base (N,3,3) the sensor's nominal (URDF) frame
    in the base frame; truth {misalignment_rotvec_rad, bias_m_per_s2, noise_m_per_s2}."""
    R = sensor_rotation_in_base @ rotvec_matrix(np.array(truth["misalignment_rotvec_rad"]))
    f = np.einsum("nji,j->ni", R, -g_base)         # Rᵀ·(−g)
    noise = rng.normal(0.0, truth["noise_m_per_s2"], f.shape) if rng is not None else 0.0
    return f + np.array(truth["bias_m_per_s2"]) + noise
