#!/usr/bin/env python3
"""A volumetric verification of an XFYZ machine tool over a shift, made by numpy from the ISO
definitions (bags/independent/iso_generator), never by metrocell: the 21 geometric errors of
ISO 230-1 (positioning, straightness and squareness as the generator defines them, and the
roll, pitch and yaw of each axis through the Abbe arms of the machine's structure with the
reference points a builder would choose), the X scale expanding and the column growing as the
shift warms the machine (ISO 230-3), and a laser tracker on the table switched on 20 minutes
before the first point (its ADM warming up).

    python3 bags/independent/verification_run.py --out DIR --seed S [--hours H]
        [--reflectors "0,0,0;150,0,0;0,0,-150"]

Writes DIR/export.csv (the tracker software's export, mm and U95), DIR/mapping.yaml (its
`bag import` mapping), DIR/mesh.csv (the verified points, commanded, mm) and DIR/truth.csv (the
machine's true error at each mesh point at 20 °C — the geometry alone, since every thermal
effect here is zero at the ISO 1 reference temperature — in µm, as the tool relative to the
workpiece, actual minus commanded), DIR/truth.json (every effect's parameters).

The program: a 5 × 5 × 3 grid over the travel (margins 10 %), visited serpentine with four
readings at each stop, round after round with short pauses until the shift's end. With
--reflectors (offsets in mm from the spindle's tool point, `;`-separated) the operator moves the
reflector to the next offset between rounds (ISO 230-1 Annex A's multi-offset verification: the
angular errors seen through Abbe arms of several lengths); the export then carries the active
tool offset of every reading, and the truth stays the tool's.
"""

import argparse
import datetime as dt
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from iso_generator import programs, shop  # noqa: E402
from iso_generator.export import write_csv, write_mapping  # noqa: E402
from iso_generator.geometric_errors import (  # noqa: E402
    AngularError,
    PositioningError,
    SquarenessError,
    StraightnessError,
)
from iso_generator.thermal import ScaleExpansion, StructureGrowth  # noqa: E402
from iso_generator.tracker import LaserTracker, Warmup  # noqa: E402
from iso_generator.xfyz_cell import ReadingContext, XFYZCell  # noqa: E402
from iso_generator.xfyz_recording import Setting, columns  # noqa: E402


def geometric_errors(rng, travel, tool_offset):
    """The 21: tens of µm and µrad, both signs."""
    um, urad = 1e-6, 1e-6
    s = lambda k: rng.uniform(-k, k)  # noqa: E731
    effects = []
    for a, (lo, hi) in zip("xyz", travel):
        effects.append(PositioningError(a, (lo, hi), progressive_per_m=s(30) * um, bow_m=s(10) * um, wave_m=s(6) * um))
        for d in "xyz":
            if d != a:
                effects.append(StraightnessError(a, d, (lo, hi), bow_m=s(8) * um, wave_m=s(5) * um))
    for name in ("EC0X", "EB0X", "EA0Y"):
        effects.append(SquarenessError(name, s(40) * urad))
    # the structure: X carries the workpiece (reference point: the table's centre); the column's
    # Y carriage carries the ram (reference: its guideway 250 mm behind the spindle, 300 mm up);
    # the ram Z carries the tool (reference: its guide 350 mm above the gauge line)
    table_centre = np.array([0.5 * travel[0][1], 0.5 * travel[1][1], tool_offset[2] - 0.06])
    structure = {
        "x": ("workpiece", ["x", "y", "z"], table_centre),
        "y": ("tool", ["z"], np.array([-0.25, 0.0, 0.30])),
        "z": ("tool", [], np.array([0.0, 0.0, 0.35])),
    }
    for a, (lo, hi) in zip("xyz", travel):
        side, carried, ref = structure[a]
        for about in "xyz":
            effects.append(AngularError(a, about, (lo, hi), side, carried, ref, trend_rad=s(30) * urad, bow_rad=s(15) * urad))
    return effects


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--hours", type=float, default=4.0)
    ap.add_argument("--reflectors", default="", help="offsets from the tool point, mm: 'x,y,z;x,y,z;...'")
    a = ap.parse_args()
    reflectors = [np.array([float(v) for v in r.split(",")]) * 1e-3 for r in a.reflectors.split(";") if r.strip()]
    rng = np.random.default_rng(90_000 + a.seed)
    setting = Setting(rng, "shift")
    setting.duration_s = a.hours * 3600.0
    setting.histories = shop.shift_histories(rng, setting.duration_s)
    travel, tool = setting.travel, setting.tool_offset
    effects = geometric_errors(rng, travel, tool)
    effects.append(ScaleExpansion("x", rng.uniform(9.0, 12.5) * 1e-6, "x_scale"))
    effects.append(StructureGrowth("column", [0.0, 0.0, -1.0], rng.uniform(2.0, 5.0) * 1e-6, rng.uniform(15, 40) * 60.0))
    setting.power_on_s = -20.0 * 60.0
    warmup = Warmup(0.0, rng.uniform(40.0, 80.0) * 1e-6, rng.uniform(60.0, 100.0) * 60.0, setting.power_on_s)
    tracker = LaserTracker(setting.tracker_R, setting.tracker_T, warmup=warmup)

    grid = [np.linspace(lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo), n) for (lo, hi), n in zip(travel, (5, 5, 3))]
    grid = [np.round(g, 4) for g in grid]  # whole 0.1 mm: the controller's program
    planner = programs.Planner(np.array([0.0, 0.0, travel[2][1]]), rng, feed_m_s=0.05)
    # where each round's readings start and which reflector they sighted: round k the k-th, in turn
    round_starts = []

    def one_round(pl):
        round_starts.append((len(pl.rows), len(round_starts) % max(len(reflectors), 1)))
        programs.serpentine_grid(pl, *grid, repeats=4)
    programs.shift_schedule(one_round, planner, setting.duration_s, rng, gap_s=(60, 4 * 60))
    readings = planner.readings()
    if reflectors:
        which = np.zeros(len(readings["t"]), dtype=int)
        for start, k in round_starts:
            which[start:] = k
        readings["tool_offset"] = tool + np.array(reflectors)[which]
    cell = XFYZCell(travel, tool, tracker, setting.histories, shop.SENSOR_NOISE_K, effects)
    sim = cell.simulate(readings, rng)

    os.makedirs(a.out, exist_ok=True)
    epoch = dt.datetime(2026, 3, 2, 6, 0, tzinfo=dt.timezone.utc).timestamp()
    cols, _ = columns(setting, readings, sim, rng, epoch)
    cols = [c for c in cols if c.key != "role"]
    write_csv(os.path.join(a.out, "export.csv"), cols)
    write_mapping(os.path.join(a.out, "mapping.yaml"), cols, "independent_verification",
                  comment="bags/independent/verification_run.py: mm -> m, U95 in mm, hPa -> Pa, %RH -> 0..1")

    mesh = np.array([[x, y, z] for z in grid[2] for y in grid[1] for x in grid[0]])
    # the truth at 20 °C: every thermal effect is zero there, so the geometry alone
    hist20 = {name: (lambda t: np.full(np.shape(t), 20.0)) for name in setting.histories}
    ctx = ReadingContext(mesh, np.ones_like(mesh), np.zeros(len(mesh)), np.zeros_like(mesh), hist20, tool)
    d = sum(e.displacement(ctx) for e in effects if e.kind not in ("thermal_scale", "thermal_growth"))
    with open(os.path.join(a.out, "truth.csv"), "w") as f:
        f.write("x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n")
        for q, e in zip(mesh, d):
            f.write(",".join(f"{v * 1e3:.4f}" for v in q) + "," + ",".join(f"{v * 1e6:.5f}" for v in e) + "\n")
    truth = {"travel_m": [list(t) for t in travel], "tool_offset_m": tool.tolist(),
             "reflectors_m": [r.tolist() for r in reflectors],
             "effects": [e.truth() for e in effects],
             "warmup": {"amplitude_m": warmup.B, "time_constant_s": warmup.tau, "power_on_s": warmup.t_on},
             "readings": int(len(readings["t"])), "duration_s": setting.duration_s}
    with open(os.path.join(a.out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
    print(f"{len(readings['t'])} readings over {planner.t / 3600:.2f} h in {len(round_starts)} rounds, travel {travel}, "
          f"tool offset {tool.tolist()}, reflectors {[r.tolist() for r in reflectors] or 'the tool'}")


if __name__ == "__main__":
    main()
