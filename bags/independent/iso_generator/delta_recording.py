"""A linear delta (rods 250 mm, radius 124 mm, a 160 mm effector box) whose diagonal rods of
towers A and B are off their nominal length (a rod pair made 60–100 µm long, another short),
followed by a tracker 0.8–1.2 m away on the bench (pose unknown). The firmware commands the
carriages from the nominal geometry; the effector sits where the true rods meet. The program:
a random 3-D set of 40 effector positions, visited three times in random order."""

import numpy as np

from .export import Column, mm, utc_stamp
from .linear_delta import carriage_heights, effector_position
from .magnitude import effect_in_noise_units
from .tracker import LaserTracker, rotation_xyz

UM = 1e-6
ROD, RADIUS = 0.250, 0.124
TRAVEL = [(-0.08, 0.08), (-0.08, 0.08), (0.0, 0.12)]


def build(rng, f, epoch_start_s):
    tool_offset = np.array([0.0, 0.0, -0.02])
    d_rod = f * np.array([rng.uniform(60, 100), -rng.uniform(50, 90), 0.0]) * UM
    pts = np.column_stack([rng.uniform(-0.07, 0.07, 40), rng.uniform(-0.07, 0.07, 40), rng.uniform(0.01, 0.11, 40)])
    pts = pts[np.hypot(pts[:, 0], pts[:, 1]) < 0.085]
    ang = rng.uniform(0, 2 * np.pi)
    dist = rng.uniform(0.8, 1.2)
    T = np.array([dist * np.cos(ang), dist * np.sin(ang), rng.uniform(0.05, 0.25)])
    R = rotation_xyz(*np.radians(rng.uniform(-0.1, 0.1, 2)), rng.uniform(-np.pi, np.pi))
    tracker = LaserTracker(R, T)
    rows, t = [], 0.0
    for r in range(3):
        for i in rng.permutation(len(pts)):
            t += rng.uniform(3, 6)
            rows.append((i, t))
    idx = np.array([i for i, _ in rows])
    times = np.array([tt for _, tt in rows])
    cmd = pts[idx]
    heights = carriage_heights(cmd, ROD, RADIUS)                 # firmware: nominal geometry
    true = effector_position(heights, ROD + d_rod, RADIUS, cmd) + tool_offset
    nominal = cmd + tool_offset
    measured, u95, _ = tracker.measure(true, times, rng)
    clean, _, _ = tracker.measure(true, times, None, noiseless=True)
    bare, _, _ = tracker.measure(nominal, times, None, noiseless=True)
    size = effect_in_noise_units(clean, bare, u95)
    cols = [Column("Point", [f"D{i + 1:02d}" for i in idx], str, "point_id"),
            Column("Role", ["fit"] * len(idx), str, "role"),
            Column("Time (UTC)", epoch_start_s + times, utc_stamp, "timestamp"),
            Column("X nominal [mm]", nominal[:, 0], mm, "nominal_x", 0.001),
            Column("Y nominal [mm]", nominal[:, 1], mm, "nominal_y", 0.001),
            Column("Z nominal [mm]", nominal[:, 2], mm, "nominal_z", 0.001),
            Column("X [mm]", measured[:, 0], mm, "measured_x", 0.001),
            Column("Y [mm]", measured[:, 1], mm, "measured_y", 0.001),
            Column("Z [mm]", measured[:, 2], mm, "measured_z", 0.001),
            Column("U95 [mm]", u95, lambda v: f"{v * 1000:.4f}", "u95", 0.001),
            Column("X cmd [mm]", cmd[:, 0], mm, "joint.x", 0.001),
            Column("Y cmd [mm]", cmd[:, 1], mm, "joint.y", 0.001),
            Column("Z cmd [mm]", cmd[:, 2], mm, "joint.z", 0.001)]
    truth = {"iso": "diagonal-rod length errors per tower (A 210 deg, B 330 deg, C 90 deg)",
             "rod_length_error_m": {"a": d_rod[0], "b": d_rod[1], "c": d_rod[2]}, "rod_m": ROD, "radius_m": RADIUS}
    return {"columns": cols, "truth": truth, "size": size, "tracker": tracker, "tool_offset": tool_offset,
            "rows": len(idx), "duration_s": float(times[-1])}
