"""How big each concealed effect is as a stationed instrument sees it: the noise-free difference
between the true robot with only that effect and the rigid URDF, in the site's level frame,
less what each setup's levelled pose (yaw, translation, tilt within the compensator's σ) fitted
to all its points absorbs; RMS per coordinate and peak (largest 3-D residual), also in units of
the instrument's σ. An effect whose RMS after that is well under σ cannot be claimed from one
recording; the scorer says which it expects diagnose to name from this.
"""

import numpy as np

from pose_fit import levelled_pose, levelled_prediction
from rotations import tilt_matrix
from true_robot import ALL_EFFECTS, nominal_prism, true_state


def sizes(urdf, rec, robot):
    R = tilt_matrix(*rec["tilt"])
    nominal = nominal_prism(urdf, rec["q"]) @ R.T
    sigma = float(np.median(rec["sigma"]))
    out = {}
    for effect in sorted(ALL_EFFECTS):
        s = true_state(urdf, rec["q"], rec["temperature_true_c"], rec["tilt"], robot, effects={effect})
        p = s["prism"] @ R.T
        raw = np.linalg.norm(p - nominal, axis=1)
        resid = np.zeros_like(p)
        for k, setup in enumerate(rec["setups"]):
            m = rec["setup_index"] == k
            seen = setup.to_instrument(p[m])            # what a noiseless instrument reads
            x = levelled_pose(nominal[m], seen, np.full((m.sum(), 3), sigma))
            resid[m] = levelled_prediction(x, nominal[m]) - seen
        rms = float(np.sqrt(np.mean(resid ** 2)))
        peak = float(np.max(np.linalg.norm(resid, axis=1)))
        out[effect] = {"raw_median_m": float(np.median(raw)), "raw_max_m": float(raw.max()),
                       "after_pose_rms_m": rms, "after_pose_peak_m": peak,
                       "after_pose_rms_in_sigma": rms / sigma, "after_pose_peak_in_sigma": peak / sigma}
    return out
