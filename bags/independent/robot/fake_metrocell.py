#!/usr/bin/env python3
"""A stand-in for the `metrocell` commands of issue 27 — for testing score_robot_suite.py's
logic only (test_scorer.py); it knows nothing of metrocell and fits nothing.

FAKE_METROCELL selects the behaviour: `complete` (every command, a check section at the noise
floor, parameters at the truth + ½σ), `miss` (fitted p95 at 3× the floor), `no_refit` (calibrate
refuses --refit as clap would), `no_check` (calibrate's JSON without `check`), `bad_import`
(bag import refuses the mapping's imu_frames), `false_claim` (diagnose also names joint_offset).
FAKE_ANSWERS is the suite's answers.json (the fake reads its numbers from it)."""

import csv
import json
import os
import sys

MODE = os.environ.get("FAKE_METROCELL", "complete")


def opt(args, name):
    return args[args.index(name) + 1] if name in args else None


def stats(p95_xy, p95_z, n):
    return {"n": n, "rms_m": p95_xy / 2, "p50_xy_m": p95_xy / 2, "p95_xy_m": p95_xy, "p95_z_m": p95_z, "max_m": 2 * p95_xy}


def calibrate(args):
    if "--refit" in args and MODE == "no_refit":
        print("error: unexpected argument '--refit' found", file=sys.stderr)
        return 2
    values = {"--model", "-o", "--json", "--refit", "--output"}
    bag = [x for i, x in enumerate(args) if i > 0 and args[i - 1] not in values and not x.startswith("-")][-1]
    with open(os.path.join(bag, "source.txt")) as f:
        source = f.read().strip()
    cond = os.path.basename(os.path.dirname(source))
    seed = os.path.basename(os.path.dirname(os.path.dirname(source))).split("_")[1]
    with open(os.environ["FAKE_ANSWERS"]) as f:
        entry = json.load(f)["seeds"][seed]
    c = entry["conditions"][cond]
    floor = c["noise_floor"]["per_setup_levelled"]["overall"]
    factor = 3.0 if MODE == "miss" else 1.0
    with open(source) as f:
        setups = sorted({row["Setup"] for row in csv.DictReader(f)})
    n = c["rows"]
    rigid = c["rigid_6dof_per_group"]["overall"]
    out = {"fit": {"iterations": 7}}
    if MODE != "no_check":
        out["check"] = {"declared": {"overall": stats(rigid["p95_xy_m"], rigid["p95_z_m"], n),
                                     "setups": {s: stats(rigid["p95_xy_m"], rigid["p95_z_m"], n // len(setups)) for s in setups}},
                        "fitted": {"overall": stats(factor * floor["p95_xy_m"], factor * floor["p95_z_m"], n),
                                   "setups": [{"setup": s, **stats(factor * floor["p95_xy_m"], factor * floor["p95_z_m"], n // len(setups))}
                                              for s in setups]}}
    robot = entry["robot"]
    k = robot["joint_compliance_rad_per_Nm"]
    out["parameters"] = [
        {"label": "joint_compliance", "parameters": {j: {"value": v + 0.5e-6, "sigma": 1e-6} for j, v in k.items()}},
        {"label": "tool_offset", "parameters": {a: {"value": v + 1e-4, "sigma": 2e-4}
                                                for a, v in zip(("dx", "dy", "dz"), robot["prism_offset_error_m"])}},
        {"label": "column_bending", "parameters": {"foot_compliance": {"value": 2e-5, "sigma": 1e-6}}}]
    with open(opt(args, "--json"), "w") as f:
        json.dump(out, f)
    with open(opt(args, "-o"), "w") as f:
        f.write("# fitted by the fake\n")
    return 0


def main():
    args = sys.argv[1:]
    if args[:2] == ["bag", "import"]:
        if MODE == "bad_import":
            print(f"error: {opt(args, '--mapping')}: unknown key `imu_frames`", file=sys.stderr)
            return 1
        os.makedirs(opt(args, "-o"), exist_ok=True)
        with open(os.path.join(opt(args, "-o"), "source.txt"), "w") as f:
            f.write(os.path.abspath(args[2]))
        return 0
    if args and args[0] == "diagnose":
        terms = ["column_bending", "tool_offset", "joint_compliance"] + (["joint_offset"] if MODE == "false_claim" else [])
        print(json.dumps({"findings": [{"term": t, "label": t} for t in terms]}))
        return 0
    if args and args[0] == "calibrate":
        return calibrate(args)
    print(f"error: unrecognized subcommand '{args[0] if args else ''}'", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
