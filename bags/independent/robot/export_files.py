"""The files a user hands metrocell: the logger's CSV export, the mapping that reads it into
metrocell's point layout (crates/bagtools/src/import.rs, module doc; the keys `setup`, `role`,
`accel.<sensor>.x|y|z` and the mapping's `imu_frames` are issue 27's, being added), the model
file (the rigid URDF, terms: []) and a model with the planned gravity terms declared free.

The export is what a total-station controller and the robot's logger, merged on time, would
give: the point name, the setup, the role, a UTC date-time, local coordinates E, N, H in mm
with their standard uncertainties in mm, the raw Hz/V [gon] and slope distance [m] (ignored by
the mapping), the commanded independent joints (column in mm, arm joints in degrees), the two
accelerometers in m/s² (their own frames), the air temperature in °C.
"""

import csv
import datetime as dt

import numpy as np

from robot_description import ARM_JOINTS, IMU_LINKS, ROOT_LINK, TIP_LINK
from total_station import GON

MAPPING_COMMENT = """Mapping of the merged total-station + robot-logger export (bags/independent/robot) onto
metrocell's point CSV layout: E/N/H and their sigmas mm -> m, the column in mm -> m, the arm's
joints in degrees -> rad, accelerations already in m/s^2 (each sensor's own frame, named in
imu_frames), the UTC date-time as it is. Hz/V/SD (the raw observations) and the group are ignored."""


def utc(epoch_s):
    return dt.datetime.fromtimestamp(float(epoch_s), dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S.%f")[:-3]


def columns(rec, epoch_start):
    """[(header, values, formatter, layout key or None, scale or None)]."""
    n = len(rec["role"])
    setup_names = [rec["setups"][s].name for s in rec["setup_index"]]
    point = [f"G{g + 1:02d}.{i + 1:03d}" for i, g in enumerate(rec["group"])]
    mm = lambda v: f"{v * 1000.0:.3f}"
    cols = [("Point", point, str, "point_id", None),
            ("Setup", setup_names, str, "setup", None),
            ("Role", list(rec["role"]), str, "role", None),
            ("Group", [f"G{g + 1:02d}" for g in rec["group"]], str, None, None),
            ("Date/Time (UTC)", epoch_start + rec["time_s"], utc, "timestamp", None)]
    for k, axis in zip(("E", "N", "H"), "xyz"):
        cols.append((f"{k} [mm]", rec["measured"][:, "xyz".index(axis)], mm, f"measured_{axis}", 0.001))
    for k, axis in zip(("E", "N", "H"), "xyz"):
        cols.append((f"s{k} [mm]", rec["sigma"][:, "xyz".index(axis)], lambda v: f"{v * 1000.0:.3f}", f"u_{axis}", 0.001))
    cols += [("Hz [gon]", rec["raw"]["hz"] / GON, lambda v: f"{v:.5f}", None, None),
             ("V [gon]", rec["raw"]["v"] / GON, lambda v: f"{v:.5f}", None, None),
             ("SD [m]", rec["raw"]["sd"], lambda v: f"{v:.5f}", None, None),
             ("column_lower [mm]", rec["q"]["column_lower"], lambda v: f"{v * 1000.0:.2f}", "joint.column_lower", 0.001)]
    for j in ARM_JOINTS:
        cols.append((f"{j} [deg]", np.degrees(rec["q"][j]), lambda v: f"{v:.5f}", f"joint.{j}", float(np.pi / 180.0)))
    for sensor in IMU_LINKS:
        for i, axis in enumerate("xyz"):
            cols.append((f"acc_{sensor}_{axis} [m/s2]", rec["accel"][sensor][:, i], lambda v: f"{v:.5f}", f"accel.{sensor}.{axis}", None))
    cols.append(("T_air [C]", rec["temperature_logged_c"], lambda v: f"{v:.2f}", "temperature.ambient", None))
    assert all(len(c[1]) == n for c in cols)
    return cols


def write_csv(path, cols):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow([c[0] for c in cols])
        for i in range(len(cols[0][1])):
            w.writerow([c[2](c[1][i]) for c in cols])


def write_mapping(path, cols):
    lines = [f"# {line}" for line in MAPPING_COMMENT.splitlines()]
    lines += ["frame_id: total_station", "source: total_station_export",
              "imu_frames: {" + ", ".join(f"{s}: {link}" for s, link in IMU_LINKS.items()) + "}", "columns:"]
    for header, _, _, key, scale in cols:
        if key is not None:
            lines.append(f'  {key}: {{column: "{header}"' + (f", scale: {scale!r}" if scale is not None else "") + "}")
    lines.append("ignore: [" + ", ".join(f'"{c[0]}"' for c in cols if c[3] is None) + "]")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


MODEL_HEAD = f"""# The user's model of the tracked mobile manipulator: the URDF from CAD (a rigid robot; the
# column's two segments one motor: column_upper mimics column_lower), a levelled total station
# whose pose per setup nobody measured, two accelerometers, the air thermometer.
# Written by bags/independent/robot/export_files.py.
name: mobile_manipulator
description: tracked mobile manipulator with a lifting column, prism on the tool read by a total station

machine:
  family: serial_arm
  serial_arm:
    urdf: {{path: robot.urdf, root_link: {ROOT_LINK}, tip_link: {TIP_LINK}}}

sensors:
  tracker: {{levelled: true, tilt_sigma: 50 urad}}
  accelerometers:
    - {{name: base, link: {IMU_LINKS['base']}}}
    - {{name: tip, link: {IMU_LINKS['tip']}}}
  thermocouples:
    - {{name: ambient, location: ambient, noise: 0.05 K, rate: 0.1 Hz}}

environment:
  ambient: {{mean: 21 degC}}
  air: {{pressure: 101.3 kPa, humidity: 45}}

program:
  joints:
    - [0.3 m, 0 deg, -60 deg, 90 deg, -30 deg, 90 deg, 0 deg]
  feed_rate: 50 mm/s
  rotary_rate: 30 deg/s
  dwell: 3 s
"""

# The planned catalog terms (issue 27) as a user would declare them to calibrate: every
# option and parameter name below is a GUESS of a convention metrocell has not fixed yet — the
# one place to change when it has (README: "conventions assumed").
GRAVITY_TERMS = """
terms:
  - id: joint_compliance             # Δθ_j = k_j·τ_j, τ_j the gravity torque from the URDF inertials [rad/(N·m)]
    options: {joints: [shoulder_pan, shoulder_lift, elbow, wrist_1, wrist_2, wrist_3]}
    params: {k_shoulder_pan: 0, k_shoulder_lift: 0, k_elbow: 0, k_wrist_1: 0, k_wrist_2: 0, k_wrist_3: 0}
  - id: column_bending               # the telescoping column's tilt under the carried moment: foot, guide pads, tube
    options: {joint: column_lower, overlaps: [800 mm, 900 mm]}
    params: {foot: 0, pads: 0, flexure: 0}
  - id: joint_backlash               # the full play b, taken up to the side of the gravity torque
    options: {joints: [shoulder_lift, elbow, wrist_1]}
    params: {b_shoulder_lift: 0, b_elbow: 0, b_wrist_1: 0}
  - id: tool_offset                  # the prism's offset error in the tool (flange) frame
    params: {dx: 0 mm, dy: 0 mm, dz: 0 mm}
  - id: link_thermal_expansion       # handbook α, not fitted (the flat recording is at one temperature)
    options: {sensor: ambient}
    params: {alpha: 23e-6 1/K}

estimation:
  link_thermal_expansion[ambient]: {free: []}
"""


def model_text(gravity_terms=False):
    return MODEL_HEAD + (GRAVITY_TERMS if gravity_terms else "\nterms: []\n")
