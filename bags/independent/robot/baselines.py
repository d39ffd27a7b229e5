"""What a recording gives without metrocell: the rigid URDF stationed per group, the floor the
instrument's noise alone sets, and the true robot stationed per setup (the oracle).

* rigid, 6 dof per group — the user's way before metrocell (issue 27: real data give p95 xy
  13–20 mm): each group's 8 fit points station a free rigid motion of the rigid URDF's prism
  points (pose_fit.rigid_pose); its 40 check points are predicted with it;
* rigid, levelled per group — the same with the instrument's pose as it stands (yaw and
  translation, tilt held by the compensator's σ) and the base taken as level (no accelerometer);
* noise floor — a perfectly known robot (its true prism positions in the site's level frame,
  the ground's tilt known) measured again and again with only the instrument's noise: each
  setup stationed (levelled pose) from its fit points, its check points predicted; the errors
  pooled over `reps` repetitions. This is issue 27's "within 1.5× of what the instrument's noise
  alone gives" for metrocell's workflow (one pose per setup);
* oracle — the same stationing on this recording's own measurements with the true robot:
  one draw of the floor (should sit near it).
Errors are predicted − measured in the instrument's frame (check_statistics.py).
"""

import numpy as np

from check_statistics import check_stats
from pose_fit import apply_rigid, levelled_pose, levelled_prediction, rigid_pose


def _per_setup(rec, err, sel):
    out = {}
    for s, setup in enumerate(rec["setups"]):
        m = sel & (rec["setup_index"] == s)
        out[setup.name] = check_stats(err[m])
    return out


def rigid_per_group(rec, mode="6dof"):
    err = np.full((len(rec["role"]), 3), np.nan)
    for g in np.unique(rec["group"]):
        fit = (rec["group"] == g) & (rec["role"] == "fit")
        chk = (rec["group"] == g) & (rec["role"] == "check")
        model, meas = rec["nominal_base"], rec["measured"]
        if mode == "6dof":
            R, t = rigid_pose(model[fit], meas[fit])
            err[chk] = apply_rigid(R, t, model[chk]) - meas[chk]
        else:
            x = levelled_pose(model[fit], meas[fit], rec["sigma"][fit])
            err[chk] = levelled_prediction(x, model[chk]) - meas[chk]
    chk = rec["role"] == "check"
    return {"overall": check_stats(err[chk]), "setups": _per_setup(rec, err, chk)}


def station_per_setup(rec, p_level, measured):
    """Errors at the check points when each setup is stationed (levelled) from its fit points."""
    err = np.full((len(rec["role"]), 3), np.nan)
    for s in range(len(rec["setups"])):
        fit = (rec["setup_index"] == s) & (rec["role"] == "fit")
        chk = (rec["setup_index"] == s) & (rec["role"] == "check")
        x = levelled_pose(p_level[fit], measured[fit], rec["sigma"][fit])
        err[chk] = levelled_prediction(x, p_level[chk]) - measured[chk]
    return err


def oracle(rec):
    err = station_per_setup(rec, rec["prism_site"], rec["measured"])
    chk = rec["role"] == "check"
    return {"overall": check_stats(err[chk]), "setups": _per_setup(rec, err, chk)}


def noise_floor(rec, rng, reps=40):
    """Pooled check statistics of `reps` noise-only re-measurements (levelled pose per setup),
    and the same with a 6-dof pose per group (the rigid baseline's stationing)."""
    chk = rec["role"] == "check"
    pooled_setup, pooled_group, per_setup = [], [], {s.name: [] for s in rec["setups"]}
    for _ in range(reps):
        meas = np.zeros_like(rec["measured"])
        for s, setup in enumerate(rec["setups"]):
            sel = rec["setup_index"] == s
            meas[sel] = setup.observe(rec["prism_site"][sel], rng)["xyz"]
        err = station_per_setup(rec, rec["prism_site"], meas)
        pooled_setup.append(err[chk])
        for s, setup in enumerate(rec["setups"]):
            per_setup[setup.name].append(err[chk & (rec["setup_index"] == s)])
        eg = np.full_like(meas, np.nan)
        for g in np.unique(rec["group"]):
            fit = (rec["group"] == g) & (rec["role"] == "fit")
            c = (rec["group"] == g) & (rec["role"] == "check")
            R, t = rigid_pose(rec["prism_site"][fit], meas[fit])
            eg[c] = apply_rigid(R, t, rec["prism_site"][c]) - meas[c]
        pooled_group.append(eg[chk])
    return {"reps": reps,
            "per_setup_levelled": {"overall": check_stats(np.concatenate(pooled_setup)),
                                   "setups": {k: check_stats(np.concatenate(v)) for k, v in per_setup.items()}},
            "per_group_6dof": {"overall": check_stats(np.concatenate(pooled_group))}}
