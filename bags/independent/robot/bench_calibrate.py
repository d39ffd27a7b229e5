"""Issue 27's speed benchmark: `metrocell calibrate` of the robot with its gravity terms, and
`metrocell diagnose` of the rigid model, on one flat-floor recording of this suite, against the
peer measured in the same run — the generator's own numpy calibration of the same recording's
fit points (reference_calibration.py: what the data allow, Levenberg–Marquardt in numpy).

    .venv/bin/python bags/independent/robot/bench_calibrate.py --metrocell target/release/metrocell \\
        --suite /tmp/robot_suite --seed 1 [--runs 5] [--all-fit]

`--all-fit` makes every waypoint a fit point (~450, the issue's "500 points") in a copy of the
export; the numpy peer always fits the recording's own fit points (its structure is fixed to
them). Prints each command's median wall time over the runs and metrocell's time over the
peer's.
"""

import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from conditions import CALIBRATION, CONDITIONS  # noqa: E402
from hidden_truth import draw_robot_truth  # noqa: E402
from recording import build_recording  # noqa: E402
from reference_calibration import calibrate  # noqa: E402
from stationing_program import make_program  # noqa: E402
from urdf_chain import Urdf  # noqa: E402


def timed(f, runs):
    out = []
    for _ in range(runs):
        t0 = time.perf_counter()
        f()
        out.append(time.perf_counter() - t0)
    return statistics.median(out), min(out), max(out)


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed: {r.stderr[-2000:]}")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--metrocell", required=True)
    p.add_argument("--suite", required=True)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--all-fit", action="store_true")
    a = p.parse_args()
    sd = os.path.join(a.suite, f"seed_{a.seed}")
    work = tempfile.mkdtemp(prefix="robot_bench_")
    csv_path = os.path.join(sd, CALIBRATION, "export.csv")
    if a.all_fit:
        rows = list(csv.reader(open(csv_path)))
        role = rows[0].index("Role")
        for row in rows[1:]:
            row[role] = "fit"
        csv_path = os.path.join(work, "all_fit.csv")
        csv.writer(open(csv_path, "w", newline="")).writerows(rows)
    bag = os.path.join(work, "bag")
    run([a.metrocell, "bag", "import", csv_path, "--mapping", os.path.join(sd, CALIBRATION, "mapping.yaml"), "-o", bag])
    n_fit = sum(1 for r in csv.DictReader(open(csv_path)) if r["Role"] == "fit")

    # the peer: the same recording rebuilt in memory exactly as the generator made it
    urdf = Urdf(os.path.join(sd, "robot.urdf"))
    program = make_program(np.random.default_rng([a.seed, 101]), urdf, target_waypoints=450, n_groups=None)
    robot = draw_robot_truth(np.random.default_rng([a.seed, 202]))
    i = [c.key for c in CONDITIONS].index(CALIBRATION)
    rec = build_recording(urdf, program, robot, CONDITIONS[i], np.random.default_rng([a.seed, 303, i]))
    peer = timed(lambda: calibrate(urdf, rec), max(1, a.runs // 2))
    cal = timed(lambda: run([a.metrocell, "calibrate", "--model", os.path.join(sd, "model_gravity.yaml"), bag, "-o", os.path.join(work, "fitted.yaml")]), a.runs)
    diag = timed(lambda: run([a.metrocell, "diagnose", "--model", os.path.join(sd, "model.yaml"), bag, "--json", os.path.join(work, "d.json")]), max(1, a.runs // 2))
    peer_fit = int((program["role"] == "fit").sum())
    print(f"metrocell calibrate (gravity terms, {n_fit} fit points, 7-joint arm): median {cal[0]:.3f} s (min {cal[1]:.3f}, max {cal[2]:.3f}); target < 2 s")
    print(f"metrocell diagnose (rigid model, {n_fit} points): median {diag[0]:.3f} s (min {diag[1]:.3f}, max {diag[2]:.3f}); target < 20 s")
    print(f"peer: numpy reference calibration ({peer_fit} fit points): median {peer[0]:.3f} s (min {peer[1]:.3f}, max {peer[2]:.3f})")
    print(f"ratio calibrate / peer: {cal[0] / peer[0]:.3f}; diagnose / peer: {diag[0] / peer[0]:.3f}")


if __name__ == "__main__":
    main()
