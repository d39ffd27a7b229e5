#!/usr/bin/env python3
"""The concealed-effect suite's case table: writes every case's cell files and the answer key.

    python3 bags/cases.py            # (re)write bags/cases/case_NN/{truth,model}.yaml, bags/answers.json
    python3 bags/cases.py --check    # exit 1 if the committed files differ from what this writes

Each case is a *truth* cell (what the twin simulates) and a *model* cell (what the user declares:
the truth minus the concealed term(s), or the truth with the declared parameters left free). The
case directories carry neutral names (case_01, ...) in a shuffled order, and nothing in a cell's
`name`/`description` or in a recording says what was concealed; the answer key (answers.json)
is the only place that does, and only the scorer reads it.

Magnitudes are realistic: peak effects of about 2-10x the tracker's per-reading noise
(sigma ~ 5 um per coordinate at 1-2 m for a + b*rho = 4 um + 0.8 um/m, 3 urad), not 100x.

Standard library only (Python >= 3.8); no YAML library is needed to write the cells.
"""

import json
import math
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

# --------------------------------------------------------------------------------------------
# Programs (explicit point lists in serpentine order; irregular X spacing so that a periodic
# screw error does not alias onto the grid, as ISO 230-2 recommends)
# --------------------------------------------------------------------------------------------

def serpentine(xs, ys, zs):
    """z outermost, then y, x innermost; x reversed on every other row, y on every other layer."""
    pts, row = [], 0
    for iz, z in enumerate(zs):
        yl = ys if iz % 2 == 0 else list(reversed(ys))
        for y in yl:
            xl = xs if row % 2 == 0 else list(reversed(xs))
            pts += [(x, y, z) for x in xl]
            row += 1
    return pts


# dense program for geometry: 13 x positions, 3 y, 3 z = 117 points
X_DENSE = [0, 55, 130, 185, 262, 318, 397, 450, 533, 590, 668, 721, 800]
GEO_POINTS = serpentine(X_DENSE, [0, 250, 500], [0, 200, 400])
# compact program for long recordings: 7 x, 2 y, 2 z = 28 points
X_SPARSE = [0, 130, 262, 397, 533, 668, 800]
TIME_POINTS = serpentine(X_SPARSE, [50, 450], [50, 350])
# denser x for the periodic error over a long recording: 11 x, 2 y, 2 z = 44 points
X_MID = [0, 73, 151, 229, 318, 390, 462, 551, 633, 711, 800]
MID_POINTS = serpentine(X_MID, [50, 450], [50, 350])
# sweeps: the whole X travel in one move, for readings taken while moving
SWEEP_POINTS = serpentine([0, 800], [0, 500], [0, 400])


def points_yaml(pts, unit="mm"):
    return "\n".join(f"    - [{x} {unit}, {y} {unit}, {z} {unit}]" for x, y, z in pts)


# --------------------------------------------------------------------------------------------
# Cell text
# --------------------------------------------------------------------------------------------

HEADER = """\
# Concealed-effect suite (bags/README.md), {role} cell of {case}.
# Written by bags/cases.py from its case table: edit the table, not this file.
# {role_text}
"""

ROLE_TEXT = {
    "truth": "What the twin simulates: the recording is made from this file.",
    "model": "What the user declares: `metrocell diagnose --model` this file against the recording.",
}

STEADY_ENV = """\
environment:
  ambient: {mean: 20.3 degC, drift: 0.05 K/h, walk_std: 0.001}
  nodes:
    - {name: table_left, time_constant: 2 h}
    - {name: table_right, time_constant: 2 h}
    - {name: column, time_constant: 1 h}
  air: {pressure: 101.3 kPa, humidity: 45}
"""

# a shift: motors and spindle heat the table and the column, the ambient drifts
THERMAL_ENV = """\
environment:
  ambient: {mean: 20.4 degC, amplitude: 0.6 K, period: 24 h, phase: -90 deg, drift: 0.15 K/h, walk_std: 0.002}
  heat_sources:
    - name: axis_motors
      duty: [{start: 0.4 h, end: 2.6 h, level: 0.7}, {start: 3.2 h, end: 5 h, level: 0.7}]
    - name: spindle
      duty: [{start: 1 h, end: 2 h, level: 0.9}, {start: 3.5 h, end: 4.5 h, level: 0.9}]
  nodes:
    - {name: table_left, time_constant: 70 min, heating: {axis_motors: 3.5 K}}
    - {name: table_right, time_constant: 95 min, heating: {axis_motors: 2.8 K, spindle: 0.6 K}}
    - {name: column, time_constant: 45 min, heating: {spindle: 3.0 K, axis_motors: 1.0 K}}
  thermal_step: 5 s
  air: {pressure: 101.3 kPa, humidity: 45}
"""

THERMOCOUPLES = """\
  thermocouples:               # location: ambient or an environment node
    - {name: ambient, location: ambient, noise: 0.02 K, rate: 0.05 Hz, calibration_uncertainty: 0.05 K}
    - {name: x_left, location: table_left, noise: 0.02 K, rate: 0.05 Hz, calibration_uncertainty: 0.05 K}
    - {name: x_right, location: table_right, noise: 0.02 K, rate: 0.05 Hz, calibration_uncertainty: 0.05 K}
    - {name: column, location: column, noise: 0.02 K, rate: 0.05 Hz, calibration_uncertainty: 0.05 K}
"""


def tracker_yaml(rate="1 Hz", pose="[-863.527 mm, 194.373 mm, 677.782 mm]", euler="[0.0339 deg, 0.0343 deg, 59.4652 deg]",
                 warmup=None, powered_on="6 h", station=None):
    lines = [
        "  tracker:",
        "    pose:                      # tracker frame in the workpiece frame: p_wp = R p_LT + T",
        f"      translation: {pose}",
        f"      euler_xyz: {euler}",
        f"    rate: {rate}",
        "    range_noise: {constant: 4 um, per_metre: 0.8 um/m}",
        "    angular_noise: 3 urad",
    ]
    if warmup:
        lines.append(f"    warmup: {warmup}")
    lines.append(f"    powered_on_before_start: {powered_on}")
    st = {"temperature_noise": "0.02 K", "pressure_noise": "5 Pa", "humidity_noise": "0.5"}
    if station:
        st = {**station, **st}
    lines.append("    station: {" + ", ".join(f"{k}: {v}" for k, v in st.items()) + "}")
    return "\n".join(lines) + "\n"


# The user knows the tracker's pose only roughly (the fit estimates it as a nuisance): model
# files carry the true pose moved by a few millimetres and a few hundredths of a degree.
POSE_ERROR_MM = (3.1, -2.4, 1.7)
POSE_ERROR_DEG = (0.021, -0.016, 0.047)


def wrap(v, unit):
    """Angles in degrees into [-180, 180) (the pose parameters' range)."""
    return (v + 180.0) % 360.0 - 180.0 if unit == "deg" else v


def roughen(tracker_text):
    """The tracker section with its pose moved by POSE_ERROR_* (units as written)."""
    import re

    def shift(match, errors, scale):
        vals = re.findall(r"(-?[0-9.]+) ?([a-z]+)", match.group(1))
        moved = [f"{wrap(float(v) + e * scale[u], u):.6g} {u}" for (v, u), e in zip(vals, errors)]
        return match.group(0).replace(match.group(1), ", ".join(moved))

    text = re.sub(r"translation: \[([^\]]*)\]", lambda m: shift(m, POSE_ERROR_MM, {"mm": 1.0, "m": 1e-3}), tracker_text, count=1)
    return re.sub(r"euler_xyz: \[([^\]]*)\]", lambda m: shift(m, POSE_ERROR_DEG, {"deg": 1.0}), text, count=1)


def cartesian_cell(case, role, *, env, program, tracker, terms, estimation="", disturbances="",
                   travel=("800 mm", "500 mm", "400 mm"), machine_rate="1 Hz", load=""):
    """A cartesian XFYZ cell (the thesis' machine layout) with a tracker and thermocouples."""
    text = HEADER.format(role=role, case=case, role_text=ROLE_TEXT[role])
    text += f"name: {case}\ndescription: XFYZ machine measured with a laser tracker\n\n"
    text += f"""\
machine:
  family: cartesian
  stacking: XFYZ
  travel: {{x: [0 mm, {travel[0]}], y: [0 mm, {travel[1]}], z: [0 mm, {travel[2]}]}}
  tool_offset: [0 mm, 0 mm, -150 mm]   # tracker target (SMR) relative to the Z carriage

sensors:
"""
    text += (roughen(tracker) if role == "model" else tracker) + THERMOCOUPLES + f"  machine_state: {{rate: {machine_rate}}}\n\n"
    text += env.replace("  air:", load + "  air:") if load else env
    text += "\n" + program.yaml() + "\n"
    text += "terms:" + (" []\n" if not terms else "\n" + terms)
    if estimation:
        text += "\nestimation:\n" + estimation
    if disturbances:
        text += "\ndisturbances:                # test-only, non-physical (crates/twin/src/disturbance.rs)\n" + disturbances
    return text


class Program:
    """A measurement program: its cell-file text and the time windows of its cycles.

    Units: points in mm, feed in mm/s, times in s. A cycle leaves home, visits the points
    (moving at the feed rate, dwelling at each) and returns home; cycles start every
    `interval` s from `start` (back to back without an interval), `cycles` of them or until
    the end of the recording.
    """

    def __init__(self, points, feed=100.0, dwell=2.0, cycles=None, interval=None, home=(0, 0, 400), start=0.0):
        self.points, self.feed, self.dwell, self.cycles, self.interval, self.home, self.start = points, feed, dwell, cycles, interval, home, start

    def cycle_length(self):
        path = [self.home] + list(self.points) + [self.home]
        moves = sum(sum((a - b) ** 2 for a, b in zip(p, q)) ** 0.5 for p, q in zip(path, path[1:]))
        return moves / self.feed + self.dwell * len(self.points)

    def windows(self, duration):
        """[start, end) of each cycle within the recording (s from its start), with 1 s margins."""
        length = self.cycle_length()
        period = max(self.interval or length, length)
        out, k = [], 0
        while self.start + k * period < duration and (self.cycles is None or k < self.cycles):
            t0 = self.start + k * period
            a, b = max(t0 - 1.0, 0.0), min(t0 + length + 1.0, duration)
            if out and a <= out[-1][1]:
                out[-1] = (out[-1][0], b)  # back-to-back cycles: one window
            else:
                out.append((a, b))
            k += 1
        return out

    def yaml(self):
        fmt = lambda v: f"{v:g}"
        text = "program:\n  points:\n" + points_yaml(self.points) + "\n"
        text += f"  feed_rate: {fmt(self.feed)} mm/s\n  dwell: {fmt(self.dwell)} s\n"
        text += "  home: [" + ", ".join(f"{fmt(v)} mm" for v in self.home) + "]\n"
        if self.start:
            text += f"  start: {fmt(self.start)} s\n"
        if self.cycles:
            text += f"  cycles: {self.cycles}\n"
        if self.interval:
            text += f"  cycle_interval: {fmt(self.interval)} s\n"
        return text


def arm_cell(case, role, *, terms, program, estimation=""):
    """A UR5 on a pedestal (published DH, crates/twin/examples/cells/serial_arm_ur5.yaml), its SMR
    followed by a tracker 2.5 m away."""
    text = HEADER.format(role=role, case=case, role_text=ROLE_TEXT[role])
    text += f"name: {case}\ndescription: six-axis arm measured with a laser tracker\n\n"
    text += """\
machine:
  family: serial_arm
  serial_arm:
    dh:
      convention: standard
      rows:
        - {d: 0.089159, alpha: 90 deg}
        - {a: -0.425}
        - {a: -0.39225}
        - {d: 0.10915, alpha: 90 deg}
        - {d: 0.09465, alpha: -90 deg}
        - {d: 0.0823}
    base: {translation: [0 m, 0 m, 0.8 m]}
    tool: {translation: [0 mm, 30 mm, 60 mm]}   # SMR on a bracket, off the flange axis
    joint_limits: [[-360 deg, 360 deg], [-360 deg, 360 deg], [-360 deg, 360 deg], [-360 deg, 360 deg], [-360 deg, 360 deg], [-360 deg, 360 deg]]

sensors:
"""
    tracker = tracker_yaml(pose="[2.5 m, 0.3 m, 1.0 m]", euler="[0 deg, 0 deg, 170 deg]")
    text += roughen(tracker) if role == "model" else tracker
    text += """\
  thermocouples:
    - {name: ambient, location: ambient, noise: 0.02 K, rate: 0.05 Hz}
  machine_state: {rate: 1 Hz}

environment:
  ambient: {mean: 20.8 degC, drift: 0.05 K/h}
  air: {pressure: 101.3 kPa, humidity: 50}

"""
    text += program + "\n" + "terms:" + (" []\n" if not terms else "\n" + terms)
    if estimation:
        text += "\nestimation:\n" + estimation
    return text


def arm_program():
    """Joint targets (deg) that turn the wrist through many orientations."""
    import itertools
    rows = []
    bases = [(-40, -100, 95), (0, -80, 110), (35, -110, 80), (70, -95, 100)]
    wrists = [(-90, -90, 0), (-60, -70, 90), (-120, -110, -90), (-30, -100, 180), (-150, -60, 45)]
    for (a, b, c), (d, e, f) in itertools.product(bases, wrists):
        rows.append(f"    - [{a} deg, {b} deg, {c} deg, {d} deg, {e} deg, {f} deg]")
    return ("program:\n  joints:\n" + "\n".join(rows) + "\n"
            "  home_joints: [0 deg, -90 deg, 90 deg, -90 deg, -90 deg, 0 deg]\n"
            "  feed_rate: 100 mm/s\n  rotary_rate: 40 deg/s\n  dwell: 3 s\n  cycles: 2\n")


def delta_cell(case, role, *, terms, program):
    """A linear delta (crates/twin/examples/cells/delta_printer.yaml) with a tracker on its bed side."""
    text = HEADER.format(role=role, case=case, role_text=ROLE_TEXT[role])
    text += f"name: {case}\ndescription: linear delta measured with a laser tracker\n\n"
    text += """\
machine:
  family: delta
  delta: {rod_length: 250 mm, radius: 124 mm}
  travel: {x: [-80 mm, 80 mm], y: [-80 mm, 80 mm], z: [0 mm, 120 mm]}
  tool_offset: [0 mm, 0 mm, -20 mm]

sensors:
"""
    tracker = tracker_yaml(pose="[1.1 m, -0.4 m, 0.3 m]", euler="[0 deg, 0 deg, 160 deg]")
    text += roughen(tracker) if role == "model" else tracker
    text += """\
  thermocouples:
    - {name: ambient, location: ambient, noise: 0.02 K, rate: 0.05 Hz}
  machine_state: {rate: 1 Hz}

environment:
  ambient: {mean: 22 degC}
  air: {pressure: 101.3 kPa, humidity: 40}

"""
    text += program.yaml() + "\n" + "terms:" + (" []\n" if not terms else "\n" + terms)
    return text


def probe_cell(case, role, *, terms, program, probe):
    """An XFYZ machine probing a part with a touch probe (no tracker): hits in several directions
    at each program point."""
    text = HEADER.format(role=role, case=case, role_text=ROLE_TEXT[role])
    text += f"name: {case}\ndescription: XFYZ machine probing a part\n\n"
    text += """\
machine:
  family: cartesian
  stacking: XFYZ
  travel: {x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}
  tool_offset: [0 mm, 0 mm, -150 mm]   # stylus tip relative to the Z carriage

sensors:
"""
    text += probe + """\
  thermocouples:
    - {name: ambient, location: ambient, noise: 0.02 K, rate: 0.05 Hz}
  machine_state: {rate: 1 Hz}

"""
    text += STEADY_ENV + "\n" + program.yaml() + "\n" + "terms:" + (" []\n" if not terms else "\n" + terms)
    return text


def probe_yaml(directions, noise="0.6 um", pretravel=None):
    text = "  probe:\n    directions: [" + ", ".join(f"[{x:g}, {y:g}, {z:g}]" for x, y, z in directions) + "]\n"
    text += f"    hit_interval: 0.5 s\n    noise: {noise}\n"
    if pretravel:
        text += "    pretravel:\n" + pretravel
    return text


_c, _d = math.cos(math.radians(45)), math.sin(math.radians(45))
# eight directions in the XY plane (45 deg apart) and one down: what a lobing study probes
PROBE_RING = [(1, 0, 0), (_c, _d, 0), (0, 1, 0), (-_c, _d, 0), (-1, 0, 0), (-_c, -_d, 0), (0, -1, 0), (_c, -_d, 0), (0, 0, -1)]
# a part's faces: +-X, +-Y and the top
PROBE_FACES = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, -1)]


# --------------------------------------------------------------------------------------------
# Terms (the catalog's configs, crates/physics/README.md)
# --------------------------------------------------------------------------------------------

T = {
    "thermal_scale": """\
  - id: thermal_scale
    options: {axis: x, sensors: [{name: x_left, position: 0 m}, {name: x_right, position: 0.8 m}]}
    params: {alpha: ALPHA}
""",
    "thermal_growth": """\
  - id: thermal_growth         # the warm column lowers the spindle (a negative growth along +z), lagging its sensor
    options: {sensor: column, direction: [0, 0, 1], lag: true}
    params: {coefficient: COEF, time_constant: TAU}
""",
    "backlash": """\
  - id: backlash
    options: {axis: AXIS}
    params: {reversal: REV}
""",
    "squareness": """\
  - id: squareness
    options: {pair: PAIR}
    params: {s: S}
""",
    "pitch_cyclic": """\
  - id: pitch_cyclic
    options: {axis: x, lead: 20 mm, harmonics: 1}
    params: {a1: A1, b1: B1}
""",
    "positioning": """\
  - id: positioning
    options: {axis: AXIS, order: 3, travel: [0 mm, TRAVEL]}
    params: {c0: 0 um, c1: C1, c2: C2, c3: C3}
""",
    "straightness": """\
  - id: straightness           # the X motion's straightness along Z
    options: {axis: x, direction: z, order: 3, travel: [0 mm, 800 mm]}
    params: {c0: 0 um, c1: 0 um, c2: C2, c3: C3}
""",
    "time_offset": """\
  - id: time_offset
    params: {latency: LAT}
""",
    "tool_offset": """\
  - id: tool_offset            # the SMR bracket's offset error, tool frame
    params: {dx: DX, dy: DY, dz: DZ}
""",
    "frame_misalignment": """\
  - id: frame_misalignment     # the part on its fixture, relative to the machine axes
    params: {rx: RX, ry: RY, rz: RZ, tx: TX, ty: TY, tz: TZ}
""",
    "delta_rod_length": """\
  - id: delta_rod_length
    params: {rod_length_a: A, rod_length_b: B, rod_length_c: 0 um}
""",
}


def term(kind, **subs):
    text = T[kind]
    for k, v in subs.items():
        text = text.replace(k.upper(), str(v))
    return text


# --------------------------------------------------------------------------------------------
# The case table
# --------------------------------------------------------------------------------------------
# Each entry: key (descriptive, never written into a cell or recording), kind, truth/model text,
# the recording plan (duration, windows to keep) and the answer.

GEO_PROGRAM = Program(GEO_POINTS, cycles=2)
COMPLIANCE = """\
  - id: compliance             # the Y carriage is a cantilever: it sags under the payload
    options: {extension_axis: y, extension_origin: 0 mm}
    params: {translational: 2e-8 m/N, rotational: 8e-8 rad/(N m), bending: 3e-7 1/(N m^2)}
"""
LOAD = "  load_force: [0 N, 0 N, {f}]     # the tool's weight on the Y carriage (N, machine frame)\n"
PRETRAVEL = """\
      options: {lobes: 3}
      params: {mean: 4 um, lobe_cos: 2 um, lobe_sin: -1.5 um, vertical: 3 um}
"""
# a 3 m gantry: 9 x positions, 3 y, 2 z; the tracker stands beyond its X = 0 end
GANTRY_TRAVEL = ("3000 mm", "1500 mm", "600 mm")
GANTRY = Program(serpentine([0, 310, 720, 1090, 1460, 1880, 2270, 2630, 3000], [0, 750, 1500], [0, 600]),
                 feed=200.0, cycles=3, home=(0, 0, 600))
GANTRY_TRACKER = "[-1500 mm, 600 mm, 900 mm]"
# the delta's effector box: 5 x 5 x 3 points
DELTA = Program(serpentine([-70, -35, 0, 35, 70], [-70, -35, 0, 35, 70], [10, 60, 110]), feed=50.0, cycles=2, home=(0, 0, 115))
# probing: 4 x 3 x 2 points over a part, 9 (ring) or 5 (faces) hits each
PROBE_PROGRAM = Program(serpentine([50, 260, 470, 680], [60, 250, 440], [40, 220]), dwell=5.0, cycles=2, home=(0, 0, 400))
ARM_JOINT_OFFSETS = """\
  - id: joint_offset           # calibrated zero offsets (declared in the model at these values)
    options: {joints: 6}
    params: {q1: 0 rad, q2: 0.12 mrad, q3: -0.09 mrad, q4: 0.05 mrad, q5: 0 rad, q6: 0 rad}
"""
SWEEP = Program(SWEEP_POINTS, feed=50.0, dwell=2.0, cycles=3)
GEO = dict(env=STEADY_ENV, program=GEO_PROGRAM, tracker=tracker_yaml())
GEO_DURATION = 720.0       # two cycles of ~5.4 min
LONG_DURATION = 5 * 3600.0  # a 5-hour shift


def case(key, kind, duration, program, truth, model, answer, more_runs=()):
    """A case; `more_runs` are further truth cells recorded after the first (an hour apart), for
    effects that need a second condition (e.g. another load)."""
    return dict(key=key, kind=kind, duration=duration, program=program, truth=truth, model=model, answer=answer or {},
                more_runs=list(more_runs))


def geo_case(key, truth_terms, model_terms="", estimation="", answer=None, kind="single", disturbances=""):
    return case(key, kind, GEO_DURATION, GEO_PROGRAM,
                lambda c, r: cartesian_cell(c, r, terms=truth_terms, disturbances=disturbances, **GEO),
                lambda c, r: cartesian_cell(c, r, terms=model_terms, estimation=estimation, **GEO), answer)


def long_case(key, points, truth_terms, model_terms="", estimation="", env=THERMAL_ENV, answer=None, kind="single",
              tracker_truth=None, tracker_model=None, disturbances="", interval=1200.0):
    tt = tracker_truth or tracker_yaml()
    tm = tracker_model or tracker_yaml()
    prog = Program(points, interval=interval, start=120.0)
    return case(key, kind, LONG_DURATION, prog,
                lambda c, r: cartesian_cell(c, r, env=env, program=prog, tracker=tt, terms=truth_terms, disturbances=disturbances),
                lambda c, r: cartesian_cell(c, r, env=env, program=prog, tracker=tm, terms=model_terms, estimation=estimation), answer)


def concealed(term_id, label, checked, truth_params):
    """One concealed effect: catalog id, label, the parameters a fit can identify (compared
    with the truth within 3 sigma) and their true values (SI)."""
    return {"term": term_id, "label": label, "checked_parameters": {p: truth_params[p] for p in checked}}


CASES = [
    # ---- single concealed effects ------------------------------------------------------------
    long_case("thermal_scale", TIME_POINTS, term("thermal_scale", alpha="10.8e-6 1/K"),
              answer={"concealed": [concealed("thermal_scale", "thermal_scale[x]", ["alpha"], {"alpha": 10.8e-6})]}),
    long_case("thermal_growth", TIME_POINTS, term("thermal_growth", coef="-6 um/K", tau="25 min"),
              answer={"concealed": [concealed("thermal_growth", "thermal_growth[column]", ["coefficient", "time_constant"],
                                              {"coefficient": -6e-6, "time_constant": 1500.0})]}),
    geo_case("backlash", term("backlash", axis="x", rev="14 um"),
             answer={"concealed": [concealed("backlash", "backlash[x]", ["reversal"], {"reversal": 14e-6})]}),
    geo_case("squareness", term("squareness", pair="xy", s="40 urad"),
             answer={"concealed": [concealed("squareness", "squareness[xy]", ["s"], {"s": 40e-6})]}),
    geo_case("pitch_cyclic", term("pitch_cyclic", a1="8 um", b1="-6 um"),
             answer={"concealed": [concealed("pitch_cyclic", "pitch_cyclic[x]", ["a1", "b1"], {"a1": 8e-6, "b1": -6e-6})]}),
    geo_case("positioning", term("positioning", axis="y", travel="500 mm", c1="15 um", c2="-8 um", c3="5 um"),
             answer={"concealed": [concealed("positioning", "positioning[y]", ["c1", "c2", "c3"], {"c1": 15e-6, "c2": -8e-6, "c3": 5e-6})]}),
    geo_case("straightness", term("straightness", c2="12 um", c3="-6 um"),
             answer={"concealed": [concealed("straightness", "straightness[x:z]", ["c2", "c3"], {"c2": 12e-6, "c3": -6e-6})]}),
    # readings taken while moving: the tracker's stream is 0.3 ms late against the controller's
    # (15 um at 50 mm/s); both streams at 2 Hz
    case("time_offset", "single", 270.0, SWEEP,
         lambda c, r: cartesian_cell(c, r, env=STEADY_ENV, program=SWEEP, tracker=tracker_yaml(rate="2 Hz"), machine_rate="2 Hz", terms=term("time_offset", lat="0.3 ms")),
         lambda c, r: cartesian_cell(c, r, env=STEADY_ENV, program=SWEEP, tracker=tracker_yaml(rate="2 Hz"), machine_rate="2 Hz", terms=""),
         {"concealed": [concealed("time_offset", "time_offset", ["latency"], {"latency": 3e-4})]}),

    # the tracker switched on just before the shift: its ranges drift A + B(1 - exp(-t/tau))
    long_case("tracker_warmup", TIME_POINTS, "", env=STEADY_ENV,
              tracker_truth=tracker_yaml(warmup="{offset: 0 um, amplitude: 40 um, time_constant: 60 min}", powered_on="0 s"),
              tracker_model=tracker_yaml(powered_on="0 s"),
              answer={"concealed": [concealed("tracker_warmup", "tracker_warmup", ["amplitude", "time_constant"],
                                              {"amplitude": 40e-6, "time_constant": 3600.0})]}),
    # a gantry 3 m long; the weather station sits in a cold draught and reads 4 K low, so the
    # tracker's index is wrong by ~3.7 ppm along every beam (up to ~17 um at 4.7 m)
    case("refraction", "single", 1500.0, GANTRY,
         lambda c, r: cartesian_cell(c, r, env=STEADY_ENV, program=GANTRY, travel=GANTRY_TRAVEL, terms="",
                                     tracker=tracker_yaml(pose=GANTRY_TRACKER, euler="[0 deg, 0 deg, 10 deg]", station={"temperature_bias": "-4 K"})),
         lambda c, r: cartesian_cell(c, r, env=STEADY_ENV, program=GANTRY, travel=GANTRY_TRAVEL, terms="",
                                     tracker=tracker_yaml(pose=GANTRY_TRACKER, euler="[0 deg, 0 deg, 10 deg]")),
         {"concealed": [concealed("refraction", "refraction", ["path_temperature_offset"], {"path_temperature_offset": 4.0})]}),
    # a UR5 whose SMR bracket is not where the model says (the joint zero offsets are calibrated
    # and declared at their true values)
    case("tool_offset", "single", 400.0, None,
         lambda c, r: arm_cell(c, r, program=arm_program(), terms=ARM_JOINT_OFFSETS + term("tool_offset", dx="20 um", dy="-15 um", dz="18 um")),
         lambda c, r: arm_cell(c, r, program=arm_program(), terms=ARM_JOINT_OFFSETS,
                               estimation="  joint_offset: {free: []}     # calibrated earlier: held at these values\n"),
         {"concealed": [concealed("tool_offset", "tool_offset", ["dx", "dy", "dz"], {"dx": 20e-6, "dy": -15e-6, "dz": 18e-6})]}),
    # a linear delta whose diagonal rods are not all the nominal length
    case("delta_rod_length", "single", 480.0, DELTA,
         lambda c, r: delta_cell(c, r, program=DELTA, terms=term("delta_rod_length", a="30 um", b="-20 um")),
         lambda c, r: delta_cell(c, r, program=DELTA, terms=""),
         {"concealed": [concealed("delta_rod_length", "delta_rod_length", ["rod_length_a", "rod_length_b", "rod_length_c"],
                                  {"rod_length_a": 30e-6, "rod_length_b": -20e-6, "rod_length_c": 0.0})]}),

    # a touch probe with 3-lobe pretravel (a kinematic seat), probed in 8 directions and down;
    # repeatability 0.6 um, lobing and mean pretravel a few um
    case("probe_pretravel", "single", 360.0, PROBE_PROGRAM,
         lambda c, r: probe_cell(c, r, program=PROBE_PROGRAM, terms="", probe=probe_yaml(PROBE_RING, pretravel=PRETRAVEL)),
         lambda c, r: probe_cell(c, r, program=PROBE_PROGRAM, terms="", probe=probe_yaml(PROBE_RING)),
         {"concealed": [concealed("probe_pretravel", "probe_pretravel", ["mean", "lobe_cos", "lobe_sin", "vertical"],
                                  {"mean": 4e-6, "lobe_cos": 2e-6, "lobe_sin": -1.5e-6, "vertical": 3e-6})]}),
    # the part sits turned and tilted on the table by a few urad (a fixture not square to the axes)
    case("frame_misalignment", "single", 360.0, PROBE_PROGRAM,
         lambda c, r: probe_cell(c, r, program=PROBE_PROGRAM, probe=probe_yaml(PROBE_FACES),
                                 terms=term("frame_misalignment", rx="4 urad", ry="-6 urad", rz="10 urad", tx="3 um", ty="-2 um", tz="2 um")),
         lambda c, r: probe_cell(c, r, program=PROBE_PROGRAM, probe=probe_yaml(PROBE_FACES), terms=""),
         {"concealed": [concealed("frame_misalignment", "frame_misalignment", ["rx", "ry", "rz"], {"rx": 4e-6, "ry": -6e-6, "rz": 10e-6})]}),

    # a cantilevered Y carriage sags under the tool's weight, d = F (c0 + c_t y^2 + c_b y^3): recorded
    # with a heavy tool (300 N) and, an hour later, a light one (50 N), as one would to see a load
    # effect at all — under one constant load it is indistinguishable from a straightness error
    case("compliance", "single", GEO_DURATION, GEO_PROGRAM,
         lambda c, r: cartesian_cell(c, r, terms=COMPLIANCE, load=LOAD.format(f="-300 N"), **GEO),
         lambda c, r: cartesian_cell(c, r, terms="", **GEO),
         {"concealed": [concealed("compliance", "compliance[y]", ["translational", "rotational", "bending"],
                                  {"translational": 2e-8, "rotational": 8e-8, "bending": 3e-7})]},
         more_runs=[lambda c, r: cartesian_cell(c, r, terms=COMPLIANCE, load=LOAD.format(f="-50 N"), **GEO)]),

    # ---- null recordings (the model is complete) ---------------------------------------------
    geo_case("null_plain", "", kind="null"),
    long_case("null_long", TIME_POINTS, "", kind="null"),
    long_case("null_thermal_declared", TIME_POINTS,
              term("thermal_scale", alpha="12.1e-6 1/K") + term("thermal_growth", coef="-3.5 um/K", tau="30 min"),
              model_terms=term("thermal_scale", alpha="11.5e-6 1/K") + term("thermal_growth", coef="-4 um/K", tau="20 min"),
              estimation="  thermal_scale[x]: {free: [alpha]}\n  thermal_growth[column]: {free: [coefficient, time_constant]}\n",
              kind="null"),
    geo_case("null_geometry_declared", term("backlash", axis="x", rev="11 um") + term("squareness", pair="xy", s="-30 urad"),
             model_terms=term("backlash", axis="x", rev="0 um") + term("squareness", pair="xy", s="0 urad"),
             estimation="  backlash[x]: {free: [reversal]}\n  squareness[xy]: {free: [s]}\n", kind="null"),

    case("null_arm", "null", 400.0, None,
         lambda c, r: arm_cell(c, r, program=arm_program(), terms=ARM_JOINT_OFFSETS),
         lambda c, r: arm_cell(c, r, program=arm_program(), terms=ARM_JOINT_OFFSETS,
                               estimation="  joint_offset: {free: []}     # calibrated earlier: held at these values\n"),
         {}),
    case("null_delta_declared", "null", 480.0, DELTA,
         lambda c, r: delta_cell(c, r, program=DELTA, terms=term("delta_rod_length", a="30 um", b="-20 um")),
         lambda c, r: delta_cell(c, r, program=DELTA, terms=term("delta_rod_length", a="0 um", b="0 um")),
         {}),

    # ---- two concealed effects ---------------------------------------------------------------
    long_case("two_backlash_growth", TIME_POINTS, term("backlash", axis="x", rev="15 um") + term("thermal_growth", coef="-5 um/K", tau="25 min"),
              kind="two", answer={"concealed": [
                  concealed("backlash", "backlash[x]", ["reversal"], {"reversal": 15e-6}),
                  concealed("thermal_growth", "thermal_growth[column]", ["coefficient", "time_constant"], {"coefficient": -5e-6, "time_constant": 1500.0})]}),
    long_case("two_pitch_scale", MID_POINTS, term("pitch_cyclic", a1="9 um", b1="-7 um") + term("thermal_scale", alpha="11.0e-6 1/K"),
              kind="two", interval=1800.0, answer={"concealed": [
                  concealed("pitch_cyclic", "pitch_cyclic[x]", ["a1", "b1"], {"a1": 9e-6, "b1": -7e-6}),
                  concealed("thermal_scale", "thermal_scale[x]", ["alpha"], {"alpha": 11.0e-6})]}),
    geo_case("two_square_position", term("squareness", pair="xz", s="-45 urad") + term("positioning", axis="y", travel="500 mm", c1="-14 um", c2="9 um", c3="0 um"),
             kind="two", answer={"concealed": [
                 concealed("squareness", "squareness[xz]", ["s"], {"s": -45e-6}),
                 concealed("positioning", "positioning[y]", ["c1", "c2"], {"c1": -14e-6, "c2": 9e-6})]}),

    # ---- effects no catalog term models (right answer: unexplained, with where) -------------
    long_case("cycle_in_time", TIME_POINTS, "", env=STEADY_ENV, kind="out_of_catalog", interval=900.0,
              disturbances="  time_cycles: [{amplitude: [0 um, 0 um, 16 um], period: 47 min, phase: 20 deg}]\n",
              answer={"unexplained": {"structure": "time", "amplitude_m": [0, 0, 16e-6], "period_s": 2820.0}}),
    geo_case("local_bump", "", kind="out_of_catalog",
             disturbances="  workspace_bumps: [{amplitude: [0 um, 18 um, 0 um], centre: [590 mm, 250 mm, 200 mm], width: 90 mm}]\n",
             answer={"unexplained": {"structure": "workspace", "amplitude_m": [0, 18e-6, 0], "centre_m": [0.59, 0.25, 0.2], "width_m": 0.09}}),
    long_case("cycle_in_time_x", TIME_POINTS, "", env=THERMAL_ENV, kind="out_of_catalog", interval=900.0,
              disturbances="  time_cycles: [{amplitude: [11 um, 0 um, 0 um], period: 21 min, phase: -40 deg}]\n",
              answer={"unexplained": {"structure": "time", "amplitude_m": [11e-6, 0, 0], "period_s": 1260.0}}),
    geo_case("corner_bump", "", kind="out_of_catalog",
             disturbances="  workspace_bumps: [{amplitude: [0 um, 0 um, -15 um], centre: [120 mm, 430 mm, 380 mm], width: 110 mm}]\n",
             answer={"unexplained": {"structure": "workspace", "amplitude_m": [0, 0, -15e-6], "centre_m": [0.12, 0.43, 0.38], "width_m": 0.11}}),
]

# A fixed shuffle of the case table (so that case numbers say nothing about the kind).
ORDER = list(range(len(CASES)))
random.Random(13).shuffle(ORDER)


def build():
    """{relative path: text} of every file this script writes."""
    assert sorted(ORDER) == list(range(len(CASES))), "ORDER must be a permutation of the case table"
    files, answers, recordings = {}, {}, {}
    for n, i in enumerate(ORDER, start=1):
        c = CASES[i]
        name = f"case_{n:02d}"
        files[f"cases/{name}/truth.yaml"] = c["truth"](name, "truth")
        runs = ["truth.yaml"]
        for k, extra in enumerate(c["more_runs"], start=2):
            runs.append(f"truth_run{k}.yaml")
            files[f"cases/{name}/{runs[-1]}"] = extra(name, "truth")
        files[f"cases/{name}/model.yaml"] = c["model"](name, "model")
        answers[name] = {"kind": c["kind"], "duration_s": c["duration"], **c["answer"]}
        windows = c["program"].windows(c["duration"]) if c["program"] else [(0.0, c["duration"])]
        recordings[name] = {"duration_s": c["duration"], "windows_s": [[round(a, 3), round(b, 3)] for a, b in windows]}
        if len(runs) > 1:
            recordings[name]["runs"] = runs
        if c["kind"] in ("null", "out_of_catalog"):
            answers[name].setdefault("concealed", [])
    files["answers.json"] = json.dumps(answers, indent=1, sort_keys=True) + "\n"
    files["recordings.json"] = json.dumps(recordings, indent=1, sort_keys=True) + "\n"
    return files


def main():
    check = "--check" in sys.argv[1:]
    stale = []
    for rel, text in build().items():
        path = os.path.join(HERE, rel)
        old = open(path).read() if os.path.exists(path) else None
        if old != text:
            stale.append(rel)
            if not check:
                os.makedirs(os.path.dirname(path), exist_ok=True)
                with open(path, "w") as f:
                    f.write(text)
    if check and stale:
        print("bags/cases.py: out of date (run python3 bags/cases.py): " + ", ".join(stale), file=sys.stderr)
        return 1
    print(("checked " if check else "wrote ") + f"{len(build())} files" + (f", {len(stale)} changed" if not check else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
