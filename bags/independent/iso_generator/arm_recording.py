"""A UR5 on an 800 mm pedestal, an SMR on a bracket on its flange, a tracker on the floor
1.6–2.4 m away (pose unknown to the user). Concealed: the bracket's offset vector is off by
(dx, dy, dz) in the flange frame (machined/assembled off by tens of µm); the arm is otherwise
as its published DH table says. The program: 24 joint configurations drawn over the reachable
front half-space with varied wrist orientations, visited twice in random order."""

import numpy as np

from .export import Column, mm, utc_stamp
from .magnitude import effect_in_noise_units
from .serial_arm import tool_point
from .tracker import LaserTracker, rotation_xyz

UM = 1e-6
BASE = np.array([0.0, 0.0, 0.8])


def build(rng, f, epoch_start_s):
    tool_nominal = np.array([round(rng.uniform(0.02, 0.04), 3), 0.0, round(rng.uniform(0.04, 0.06), 3)])
    error = f * np.array([rng.uniform(25, 40), -rng.uniform(25, 40), rng.uniform(25, 40)]) * UM * np.sign(rng.uniform(-1, 1, 3))
    lim = np.radians([[-60, 60], [-130, -50], [40, 130], [-180, 0], [60, 120], [-180, 180]])
    configs = np.array([[rng.uniform(a, b) for a, b in lim] for _ in range(24)])
    configs[::2, 4] *= -1.0                                 # wrist flipped on half of them
    # the tracker in front of the arm, facing it, levelled
    ang = rng.uniform(-0.4, 0.4)
    dist = rng.uniform(1.6, 2.4)
    T = np.array([dist * np.cos(ang), dist * np.sin(ang), rng.uniform(0.9, 1.3)])
    R = rotation_xyz(*np.radians(rng.uniform(-0.1, 0.1, 2)), ang + np.pi + rng.uniform(-0.5, 0.5))
    tracker = LaserTracker(R, T)
    rows, t = [], 0.0
    for r in range(2):
        for i in rng.permutation(len(configs)):
            t += rng.uniform(6, 12)
            for _ in range(1 + int(rng.random() < 0.3)):
                t += rng.uniform(0.8, 1.5)
                rows.append((i, t))
    idx = np.array([i for i, _ in rows])
    times = np.array([tt for _, tt in rows])
    q = configs[idx]
    nominal = np.array([tool_point(j, BASE, tool_nominal) for j in q])
    true = np.array([tool_point(j, BASE, tool_nominal + error) for j in q])
    measured, u95, _ = tracker.measure(true, times, rng)
    clean, _, _ = tracker.measure(true, times, None, noiseless=True)
    bare, _, _ = tracker.measure(nominal, times, None, noiseless=True)
    size = effect_in_noise_units(clean, bare, u95)
    ambient = np.round(21.0 + 0.3 * times / 3600 + rng.normal(0, 0.02, len(times)), 2)
    cols = [Column("Point", [f"C{i + 1:02d}" for i in idx], str, "point_id"),
            Column("Role", ["fit"] * len(idx), str, "role"),
            Column("Time (UTC)", epoch_start_s + times, utc_stamp, "timestamp"),
            Column("X nominal [mm]", nominal[:, 0], mm, "nominal_x", 0.001),
            Column("Y nominal [mm]", nominal[:, 1], mm, "nominal_y", 0.001),
            Column("Z nominal [mm]", nominal[:, 2], mm, "nominal_z", 0.001),
            Column("X [mm]", measured[:, 0], mm, "measured_x", 0.001),
            Column("Y [mm]", measured[:, 1], mm, "measured_y", 0.001),
            Column("Z [mm]", measured[:, 2], mm, "measured_z", 0.001),
            Column("U95 [mm]", u95, lambda v: f"{v * 1000:.4f}", "u95", 0.001)]
    for k in range(6):
        cols.append(Column(f"J{k + 1} [deg]", np.degrees(q[:, k]), lambda v: f"{v:.5f}", f"joint.joint_{k + 1}", float(np.pi / 180.0)))
    cols.append(Column("T ambient [C]", ambient, lambda v: f"{v:.2f}", "temperature.ambient"))
    truth = {"iso": "error of the SMR offset vector in the flange frame (DH flange frame of joint 6)",
             "tool_nominal_m": tool_nominal.tolist(), "error_flange_m": error.tolist()}
    return {"columns": cols, "truth": truth, "size": size, "tracker": tracker, "tool_nominal": tool_nominal,
            "rows": len(idx), "duration_s": float(times[-1])}
