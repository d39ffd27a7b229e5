"""A reference calibration in numpy: the true model's *structure* (the generator's own physics,
its parameters unknown) fitted the way issue 27 asks metrocell to — physics from the flat-floor
recording's fit points with one levelled pose per setup, then on every other ground only the
setups' poses refitted from that recording's fit points, the check points predicted.

It shows what the data allow (not how metrocell must do it): if this reaches the noise floor,
the recordings hold what is needed; if not, the floor is not reachable from these fit points.

Unknowns (each with a weak zero-mean prior, its σ in brackets, to keep unidentifiable ones finite):
  k_j of the six arm joints [1e-4 rad/(N·m)]; backlash b_j of shoulder_lift, elbow, wrist_1
  [2 mrad]; the column's foot compliance [1e-4 rad/(N·m)], the two overlaps' pad compliances
  1/k_pad [1e-6 m/N] and 1/EI [1e-5 1/(N·m²)]; the prism offset error [20 mm]; the base
  accelerometer's alignment as a tilt offset (roll, pitch) [20 mrad];
  per setup: yaw, translation, the instrument's tilt [prior 5e-5 rad].
Known: the URDF, α from the handbook (aluminium 23e-6, steel 11.5e-6 /K — not the truth), the
ground's tilt from the base accelerometer's mean reading over the recording.
"""

import numpy as np

from least_squares import levenberg_marquardt
from pose_fit import levelled_pose, levelled_prediction
from robot_description import ALPHA, ARM_JOINTS
from rotations import tilt_matrix
from check_statistics import check_stats
from true_robot import true_state

BACKLASH_JOINTS = ("shoulder_lift", "elbow", "wrist_1")
N_PHYS = 6 + 3 + 4 + 3 + 2


def tilt_from_accelerometer(mean_reading, offset):
    """(roll, pitch) of R_WB = Rx(roll)·Ry(pitch) whose R_WBᵀ·ẑ is the reading's direction
    (the specific force points up): f̂ = (−sin p·cos r, sin r, cos p·cos r); less the
    alignment offset."""
    f = mean_reading / np.linalg.norm(mean_reading)
    return float(np.arcsin(f[1]) - offset[0]), float(np.arctan2(-f[0], f[2]) - offset[1])


def unpack(theta):
    k = dict(zip(ARM_JOINTS, theta[0:6] * 1e-4))
    b = dict(zip(BACKLASH_JOINTS, theta[6:9] * 2e-3))
    c = theta[9:13]
    col = {"foot_compliance_rad_per_Nm": c[0] * 1e-4,
           "overlap_pad_stiffness_N_per_m": [1.0 / max(c[1] * 1e-6, 1e-12), 1.0 / max(c[2] * 1e-6, 1e-12)],
           "flexural_rigidity_Nm2": 1.0 / max(c[3] * 1e-5, 1e-15)}
    robot = {"joint_compliance_rad_per_Nm": k, "joint_backlash_rad": b, "column": col,
             "prism_offset_error_m": (theta[13:16] * 2e-2).tolist(),
             "alpha_per_K": {"aluminium": ALPHA["aluminium"], "steel": ALPHA["steel"]}}
    return robot, theta[16:18] * 2e-2


def predict_level(urdf, rec, sel, theta):
    """Predicted prism positions in the site's level frame for the rows sel."""
    robot, offset = unpack(theta)
    tilt = tilt_from_accelerometer(rec["accel"]["base"].mean(axis=0), offset)
    q = {j: v[sel] for j, v in rec["q"].items()}
    s = true_state(urdf, q, rec["temperature_logged_c"][sel], tilt, robot)
    return s["prism"] @ tilt_matrix(*tilt).T


def calibrate(urdf, rec):
    fit = rec["role"] == "fit"
    n_setups = len(rec["setups"])
    setup = rec["setup_index"][fit]
    meas, sigma = rec["measured"][fit], rec["sigma"][fit]
    theta0 = np.zeros(N_PHYS)
    theta0[9:13] = [0.1, 0.1, 0.1, 0.1]       # start soft-ish, away from the 1/x pole
    # start the poses from the rigid model
    p0 = predict_level(urdf, rec, fit, theta0)
    poses0 = [levelled_pose(p0[setup == s], meas[setup == s], sigma[setup == s]) for s in range(n_setups)]
    x0 = np.concatenate([theta0] + poses0)

    def residual(x):
        theta = x[:N_PHYS]
        p = predict_level(urdf, rec, fit, theta)
        r = []
        for s in range(n_setups):
            xs = x[N_PHYS + 6 * s: N_PHYS + 6 * s + 6]
            m = setup == s
            r.append(((levelled_prediction(xs, p[m]) - meas[m]) / sigma[m]).ravel())
            r.append(xs[1:3] / 5e-5)
        r.append(theta)                     # the weak priors (unit σ in the scaled units)
        return np.concatenate(r)

    scale = np.concatenate([np.full(N_PHYS, 0.01)] + [np.array([1e-3, 1e-5, 1e-5, 1e-3, 1e-3, 1e-3])] * n_setups)
    out = levenberg_marquardt(residual, x0, scale=scale, max_iter=40)
    theta = out["x"][:N_PHYS]
    sd = np.sqrt(np.diag(out["covariance"]))[:N_PHYS]
    return theta, sd, out


def restation_and_check(urdf, rec, theta):
    """Poses refitted per setup from this recording's fit points, check points predicted."""
    allrows = np.ones(len(rec["role"]), bool)
    p = predict_level(urdf, rec, allrows, theta)
    err = np.full((len(p), 3), np.nan)
    for s in range(len(rec["setups"])):
        fit = (rec["setup_index"] == s) & (rec["role"] == "fit")
        chk = (rec["setup_index"] == s) & (rec["role"] == "check")
        x = levelled_pose(p[fit], rec["measured"][fit], rec["sigma"][fit])
        err[chk] = levelled_prediction(x, p[chk]) - rec["measured"][chk]
    chk = rec["role"] == "check"
    return {"overall": check_stats(err[chk]),
            "setups": {st.name: check_stats(err[chk & (rec["setup_index"] == s)]) for s, st in enumerate(rec["setups"])}}


def recovered(theta, sd):
    """The fitted physics in physical units with σ, for the answer key."""
    out = {}
    for i, j in enumerate(ARM_JOINTS):
        out[f"joint_compliance.{j}_rad_per_Nm"] = (theta[i] * 1e-4, sd[i] * 1e-4)
    for i, j in enumerate(BACKLASH_JOINTS):
        out[f"joint_backlash.{j}_rad"] = (theta[6 + i] * 2e-3, sd[6 + i] * 2e-3)
    out["column.foot_compliance_rad_per_Nm"] = (theta[9] * 1e-4, sd[9] * 1e-4)
    out["column.overlap1_pad_compliance_m_per_N"] = (theta[10] * 1e-6, sd[10] * 1e-6)
    out["column.overlap2_pad_compliance_m_per_N"] = (theta[11] * 1e-6, sd[11] * 1e-6)
    out["column.inverse_flexural_rigidity_per_Nm2"] = (theta[12] * 1e-5, sd[12] * 1e-5)
    for i, a in enumerate("xyz"):
        out[f"prism_offset_error.{a}_m"] = (theta[13 + i] * 2e-2, sd[13 + i] * 2e-2)
    out["base_accelerometer_tilt_offset.roll_rad"] = (theta[16] * 2e-2, sd[16] * 2e-2)
    out["base_accelerometer_tilt_offset.pitch_rad"] = (theta[17] * 2e-2, sd[17] * 2e-2)
    return {k: {"value": float(v), "sigma": float(s)} for k, (v, s) in out.items()}
