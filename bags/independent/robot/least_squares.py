"""Levenberg–Marquardt on a residual function, with a forward-difference Jacobian — small
dense problems only (a pose: 4–6 unknowns; the reference calibration: ~50). numpy only.

Minimises ½‖r(x)‖² (Marquardt 1963): step (JᵀJ + λ·diag(JᵀJ))·δ = −Jᵀr, λ shrunk on success
and grown on failure. `scale` gives each unknown's typical size (the difference step and the
damping are relative to it). Returns x, the final residual, J and the covariance (JᵀJ)⁻¹ of x
(the residuals whitened: the covariance of a weighted fit).
"""

import numpy as np


def jacobian(fun, x, r0, scale):
    J = np.empty((len(r0), len(x)))
    for i in range(len(x)):
        h = 1e-6 * scale[i]
        xp = x.copy()
        xp[i] += h
        J[:, i] = (fun(xp) - r0) / h
    return J


def levenberg_marquardt(fun, x0, scale=None, max_iter=50, tol=1e-10):
    x = np.asarray(x0, dtype=float).copy()
    scale = np.ones_like(x) if scale is None else np.asarray(scale, dtype=float)
    r = fun(x)
    cost = r @ r
    lam = 1e-3
    for _ in range(max_iter):
        J = jacobian(fun, x, r, scale)
        A = J.T @ J
        g = J.T @ r
        d = np.diag(A).copy()
        d[d <= 0] = 1.0
        improved = False
        for _ in range(12):
            try:
                step = -np.linalg.solve(A + lam * np.diag(d), g)
            except np.linalg.LinAlgError:
                lam *= 10
                continue
            r_new = fun(x + step)
            c_new = r_new @ r_new
            if c_new < cost:
                x, r, improved = x + step, r_new, True
                rel = (cost - c_new) / max(cost, 1e-300)
                cost = c_new
                lam = max(lam / 10, 1e-9)
                break
            lam *= 10
        if not improved or rel < tol:
            break
    J = jacobian(fun, x, r, scale)
    try:
        cov = np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        cov = np.linalg.pinv(J.T @ J)
    return {"x": x, "residual": r, "cost": cost, "jacobian": J, "covariance": cov}
