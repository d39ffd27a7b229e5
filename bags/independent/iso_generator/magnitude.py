"""How big a concealed effect is, in units of the noise, as a fit with an unknown tracker pose
can see it: the noise-free difference between the readings with and without the effect, less
the best rigid motion (a pose fit absorbs that part); its peak (largest 3-D residual) and RMS
per coordinate, each divided by the median per-coordinate σ of the readings."""

import numpy as np


def rigid_residual(diff, points):
    """diff − (ω × p + t) at the least-squares ω, t (small rotation): (N,3)."""
    n = len(points)
    A = np.zeros((3 * n, 6))
    px, py, pz = points[:, 0], points[:, 1], points[:, 2]
    # ω × p = (ωy pz − ωz py, ωz px − ωx pz, ωx py − ωy px)
    A[0::3, 1], A[0::3, 2], A[0::3, 3] = pz, -py, 1.0
    A[1::3, 0], A[1::3, 2], A[1::3, 4] = -pz, px, 1.0
    A[2::3, 0], A[2::3, 1], A[2::3, 5] = py, -px, 1.0
    b = diff.reshape(-1)
    x, *_ = np.linalg.lstsq(A, b, rcond=None)
    return (b - A @ x).reshape(-1, 3)


def effect_in_noise_units(with_effect, without_effect, u95):
    """{rms_m, peak_m, sigma_m, peak_in_noise, rms_in_noise} of the effect after the best rigid motion."""
    diff = with_effect - without_effect
    r = rigid_residual(diff, without_effect)
    rms = float(np.sqrt(np.mean(r ** 2)))
    peak = float(np.max(np.linalg.norm(r, axis=1)))
    sigma = float(np.median(u95) / 2.0)
    return {"effect_rms_m": rms, "effect_peak_m": peak, "noise_sigma_m": sigma,
            "effect_peak_in_noise": peak / sigma, "effect_rms_in_noise": rms / sigma}
