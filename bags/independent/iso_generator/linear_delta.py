"""A linear delta (three vertical towers, carriages with parallelogram rods to the effector).

Tower i stands at angle φ_i (210°, 330°, 90°: the firmware convention of Marlin, towers A, B,
C) on a circle of radius R (the horizontal distance from the effector's centre to a carriage's
rod joint line when centred, DELTA_RADIUS). The firmware commands carriage heights from the
nominal geometry (inverse kinematics); the effector sits where rods of the *true* lengths meet
(forward kinematics: trilateration). The rods keep the effector level, so the nozzle/SMR below
it is a constant offset.
"""

import numpy as np

TOWER_ANGLES = np.radians([210.0, 330.0, 90.0])


def tower_xy(radius):
    return np.stack([radius * np.cos(TOWER_ANGLES), radius * np.sin(TOWER_ANGLES)], axis=1)


def carriage_heights(p, rod_length, radius):
    """Inverse kinematics: the carriage height of each tower for effector centre p (N,3)."""
    txy = tower_xy(radius)
    dx = p[:, None, 0] - txy[None, :, 0]
    dy = p[:, None, 1] - txy[None, :, 1]
    return p[:, 2:3] + np.sqrt(rod_length ** 2 - dx ** 2 - dy ** 2)


def effector_position(heights, rod_lengths, radius, guess):
    """Forward kinematics: the effector centre where rods of lengths rod_lengths (3,) from the
    carriages at `heights` (N,3) meet (Newton from `guess`, to 1e-13 m)."""
    txy = tower_xy(radius)
    p = np.array(guess, dtype=float)
    L = np.asarray(rod_lengths, dtype=float)
    for _ in range(30):
        c = np.concatenate([np.broadcast_to(txy, (len(p), 3, 2)), heights[:, :, None]], axis=2)   # (N,3,3)
        diff = p[:, None, :] - c
        r = np.sum(diff ** 2, axis=2) - L[None, :] ** 2
        J = 2.0 * diff
        step = np.linalg.solve(J, r[:, :, None])[:, :, 0]
        p = p - step
        if np.max(np.abs(step)) < 1e-13:
            break
    return p
