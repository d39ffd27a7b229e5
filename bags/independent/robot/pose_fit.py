"""Stationing: the instrument's pose relative to the robot from points the model predicts and
the instrument measured.

* `rigid_pose` — the free rigid motion (rotation and translation, 6 dof) of least squares
  (Kabsch 1976 / Arun et al. 1987 by SVD): measured ≈ R·model + t. What a user with a rigid
  URDF and no level does with one group's 8 fit points.
* `levelled_pose` — the total station's pose as it stands: yaw ψ and translation free, the
  tilt ε held near zero by the compensator's σ (a prior ε/σ_ε as extra residuals), the model's
  points given in the site's level frame:  measured = R_sᵀ·(p_level − T_s),
  R_s = Rz(ψ)·Rx(ε_x)·Ry(ε_y) — as total_station.py defines the setup. Residuals weighted by
  each point's per-axis σ.
"""

import numpy as np

from least_squares import levenberg_marquardt
from rotations import rot_z, tilt_matrix


def rigid_pose(model, measured):
    """(R, t) with measured ≈ R·model + t (unweighted; the σ are nearly isotropic)."""
    cm, cd = model.mean(axis=0), measured.mean(axis=0)
    H = (model - cm).T @ (measured - cd)
    U, _, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    return R, cd - R @ cm


def apply_rigid(R, t, model):
    return model @ R.T + t


def levelled_prediction(x, p_level):
    """x = (ψ, ε_x, ε_y, T_x, T_y, T_z): points in the instrument frame."""
    R = rot_z(x[0]) @ tilt_matrix(x[1], x[2])
    return (p_level - x[3:6]) @ R


def levelled_pose(p_level, measured, sigma, tilt_sigma=5e-5, free_tilt=True):
    """Fit x = (ψ, ε_x, ε_y, T) to measured (N,3) [instrument frame] of the points p_level (N,3)
    [site level frame], σ (N,3). Returns x."""
    # start: the yaw of the best rigid motion instrument → level (p_level ≈ R·measured + T)
    R0, t0 = rigid_pose(measured, p_level)
    psi0 = np.arctan2(R0[1, 0], R0[0, 0])
    x0 = np.array([psi0, 0.0, 0.0, *t0])

    def residual(x):
        r = ((levelled_prediction(x, p_level) - measured) / sigma).ravel()
        prior = x[1:3] / tilt_sigma if free_tilt else x[1:3] * 1e9
        return np.concatenate([r, prior])

    fit = levenberg_marquardt(residual, x0, scale=np.array([1e-3, 1e-5, 1e-5, 1e-3, 1e-3, 1e-3]), max_iter=30)
    return fit["x"]
