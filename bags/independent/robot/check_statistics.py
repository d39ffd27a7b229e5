"""The check-point statistics of issue 27's JSON `check` section, computed the same way here:
errors e = predicted − measured in the instrument's levelled frame (x, y horizontal, z up);
  n        number of check points,
  rms_m    RMS of the 3-D error |e| (√mean|e|²),
  p50_xy_m, p95_xy_m   50th/95th percentile of the horizontal error √(e_x² + e_y²),
  p95_z_m  95th percentile of |e_z|,
  max_m    largest |e|.
(metrocell may define rms_m per coordinate — √mean(e_x² + e_y² + e_z²)/√3 — the scorer prints
what the JSON says and does not compare rms.)
"""

import numpy as np


def check_stats(err):
    err = np.asarray(err, dtype=float).reshape(-1, 3)
    if len(err) == 0:
        return {"n": 0, "rms_m": None, "p50_xy_m": None, "p95_xy_m": None, "p95_z_m": None, "max_m": None}
    xy = np.hypot(err[:, 0], err[:, 1])
    norm = np.linalg.norm(err, axis=1)
    return {"n": int(len(err)), "rms_m": float(np.sqrt(np.mean(norm ** 2))), "p50_xy_m": float(np.percentile(xy, 50)),
            "p95_xy_m": float(np.percentile(xy, 95)), "p95_z_m": float(np.percentile(np.abs(err[:, 2]), 95)),
            "max_m": float(norm.max())}
