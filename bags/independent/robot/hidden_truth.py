"""What the true robot of one seed is — drawn once per seed and the same on every ground:
the same machine measured on seven grounds.

Magnitudes (see the README for what they give at the prism):
* joint compliance k_j [rad/(N·m)]: shoulder_lift 1.4–2.0e-5, elbow 1.1–1.7e-5 (the softest),
  wrist_1 5–10e-6, wrist_2 3–7e-6, shoulder_pan 2–6e-6 (about the vertical: loaded only on a
  tilt), wrist_3 1–3e-6;
* backlash b_j [rad]: 0.1–0.5 mrad on shoulder_lift, elbow and (two seeds in three) wrist_1;
* the column: foot 0.9–1.3e-5 rad/(N·m); guide pads 4–7e6 N/m per overlap (0.5e-6 rad/(N·m)
  retracted, ~9e-6 at full extension); EI 3.5–5e5 N·m² (an aluminium-steel tube of ~140 mm);
* the prism's offset from the flange off the drawing by 2.5–5 mm per axis, random signs;
* α: aluminium 22–24e-6 /K, steel 11–12.5e-6 /K;
* the accelerometers' mounting misalignment 1–5 mrad (random axis), bias 0.01–0.05 m/s² per axis.
"""

import numpy as np


def _signed(rng, lo, hi, n=None):
    size = () if n is None else n
    return rng.uniform(lo, hi, size) * rng.choice([-1.0, 1.0], size)


def _accelerometer(rng):
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    return {"misalignment_rotvec_rad": (axis * rng.uniform(1e-3, 5e-3)).tolist(),
            "bias_m_per_s2": _signed(rng, 0.01, 0.05, 3).tolist(),
            "noise_m_per_s2": 0.005}


def draw_robot_truth(rng):
    k = {"shoulder_pan": rng.uniform(2e-6, 6e-6), "shoulder_lift": rng.uniform(1.6e-5, 2.4e-5),
         "elbow": rng.uniform(1.4e-5, 2.2e-5), "wrist_1": rng.uniform(5e-6, 1e-5),
         "wrist_2": rng.uniform(3e-6, 7e-6), "wrist_3": rng.uniform(1e-6, 3e-6)}
    backlash = {"shoulder_lift": rng.uniform(1e-4, 5e-4), "elbow": rng.uniform(1e-4, 5e-4)}
    if rng.random() < 2.0 / 3.0:
        backlash["wrist_1"] = rng.uniform(1e-4, 5e-4)
    column = {"foot_compliance_rad_per_Nm": rng.uniform(2.0e-5, 2.6e-5),
              "overlap_pad_stiffness_N_per_m": [rng.uniform(3e6, 5e6), rng.uniform(3e6, 5e6)],
              "flexural_rigidity_Nm2": rng.uniform(3e5, 4e5)}
    return {
        "joint_compliance_rad_per_Nm": k,
        "joint_backlash_rad": backlash,
        "column": column,
        "prism_offset_error_m": _signed(rng, 2.5e-3, 4.5e-3, 3).tolist(),
        "alpha_per_K": {"aluminium": rng.uniform(22e-6, 24e-6), "steel": rng.uniform(11e-6, 12.5e-6)},
        "accelerometers": {"base": _accelerometer(rng), "tip": _accelerometer(rng)},
    }
