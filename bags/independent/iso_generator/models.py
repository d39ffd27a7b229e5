"""The user's model files: what a user knows and declares about the machine — its nominal
geometry, the names of the sensors the export logs — and no error terms. The tracker's pose is
unknown: the points arrive in the tracker's own frame and the fit registers them.

Format: the cell files of crates/twin/examples/cells/*.yaml (their public examples);
`environment` and `program` are required by that format, diagnose reads the machine, the
sensors' names and the terms.
"""

from .export import yaml_mm

THERMOCOUPLES = """  thermocouples:
    - {name: x_scale, location: ambient, noise: 0.02 K, rate: 0.1 Hz}
    - {name: column,  location: ambient, noise: 0.02 K, rate: 0.1 Hz}
    - {name: air,     location: ambient, noise: 0.03 K, rate: 0.1 Hz}
    - {name: station, location: ambient, noise: 0.05 K, rate: 0.1 Hz}
"""

FOOTER = """
environment:
  ambient: {mean: 20 degC}
  air: {pressure: 95 kPa, humidity: 45}

program:
  points:
    - [0 mm, 0 mm, 0 mm]
  feed_rate: 50 mm/s
  dwell: 1 s
"""


def xfyz_model(name, travel, tool_offset, terms_yaml="terms: []\n", extra_comment=""):
    t = travel
    return f"""# The user's model of the machine the export {name} came from: a nominal XFYZ machine tool,
# no error terms declared; the tracker stood on the table in a pose nobody measured (the points
# are in the tracker's frame). {extra_comment}
name: {name}
description: XFYZ machine verified with a laser tracker standing on its table

machine:
  family: cartesian
  stacking: XFYZ
  travel: {{x: [{yaml_mm(t[0][0])}, {yaml_mm(t[0][1])}], y: [{yaml_mm(t[1][0])}, {yaml_mm(t[1][1])}], z: [{yaml_mm(t[2][0])}, {yaml_mm(t[2][1])}]}}
  tool_offset: [{yaml_mm(tool_offset[0])}, {yaml_mm(tool_offset[1])}, {yaml_mm(tool_offset[2])}]   # the SMR below the Z carriage at q = 0

sensors:
{THERMOCOUPLES}{FOOTER}
{terms_yaml}"""


def arm_model(name, tool_nominal):
    return f"""# The user's model of the UR5 the export {name} came from: the published standard DH table,
# the pedestal, the SMR bracket's nominal offset; no error terms; the tracker's pose unknown.
name: {name}
description: UR5 on a pedestal, SMR on the flange, followed by a laser tracker

machine:
  family: serial_arm
  serial_arm:
    dh:
      convention: standard
      rows:
        - {{d: 0.089159, alpha: 90 deg}}
        - {{a: -0.425}}
        - {{a: -0.39225}}
        - {{d: 0.10915, alpha: 90 deg}}
        - {{d: 0.09465, alpha: -90 deg}}
        - {{d: 0.0823}}
    base:
      translation: [0 m, 0 m, 0.8 m]
    tool:
      translation: [{yaml_mm(tool_nominal[0])}, {yaml_mm(tool_nominal[1])}, {yaml_mm(tool_nominal[2])}]
    joint_limits:
      - [-360 deg, 360 deg]
      - [-360 deg, 360 deg]
      - [-360 deg, 360 deg]
      - [-360 deg, 360 deg]
      - [-360 deg, 360 deg]
      - [-360 deg, 360 deg]

sensors:
  thermocouples:
    - {{name: ambient, location: ambient, noise: 0.02 K, rate: 0.1 Hz}}

environment:
  ambient: {{mean: 21 degC}}
  air: {{pressure: 95 kPa, humidity: 45}}

program:
  joints:
    - [0 deg, -90 deg, 90 deg, -90 deg, -90 deg, 0 deg]
  home_joints: [0 deg, -90 deg, 0 deg, -90 deg, 0 deg, 0 deg]
  feed_rate: 100 mm/s
  rotary_rate: 30 deg/s
  dwell: 1 s

terms: []
"""


def delta_model(name, rod, radius, travel, tool_offset):
    t = travel
    return f"""# The user's model of the linear delta the export {name} came from: nominal rods and radius,
# no error terms; the tracker's pose unknown.
name: {name}
description: linear delta followed by a laser tracker

machine:
  family: delta
  delta: {{rod_length: {yaml_mm(rod)}, radius: {yaml_mm(radius)}}}
  travel: {{x: [{yaml_mm(t[0][0])}, {yaml_mm(t[0][1])}], y: [{yaml_mm(t[1][0])}, {yaml_mm(t[1][1])}], z: [{yaml_mm(t[2][0])}, {yaml_mm(t[2][1])}]}}
  tool_offset: [{yaml_mm(tool_offset[0])}, {yaml_mm(tool_offset[1])}, {yaml_mm(tool_offset[2])}]

sensors:
  thermocouples:
    - {{name: ambient, location: ambient, noise: 0.05 K, rate: 0.1 Hz}}

environment:
  ambient: {{mean: 21 degC}}
  air: {{pressure: 95 kPa, humidity: 45}}

program:
  points:
    - [0 mm, 0 mm, 50 mm]
  feed_rate: 50 mm/s
  dwell: 1 s

terms: []
"""
