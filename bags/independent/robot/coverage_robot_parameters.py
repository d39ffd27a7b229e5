#!/usr/bin/env python3
"""Do metrocell's stated uncertainties of the robot's physics cover the truth at their stated rate?

    .venv/bin/python bags/independent/robot/coverage_robot_parameters.py --metrocell target/release/metrocell \\
        --suite DIR [--seeds 3 4 ...] [--calibrate-model model_gravity.yaml] [--out coverage.json]

Per seed of a suite written by generate_robot_suite.py (one true robot per seed, drawn anew): the
flat-floor recording is imported and `metrocell calibrate --model <model> BAG --json` fits it; each
judged parameter (truth_matching.py: joint compliance per joint, backlash per joint, the prism
offset per axis) gives z = (fitted − truth)/σ. Over seeds the fraction with |z| ≤ 1, 2, 3 is set
beside the normal's 68.3 %, 95.4 %, 99.7 %, with the binomial interval (Wilson, 95 %) of each
measured fraction: a stated rate outside the interval means the σ are wrong (too small when the
fraction is low). Every seed is an independent robot and recording, so the z's of one parameter
across seeds are independent draws; the parameters of one seed are not independent of each other
(their covariance), which is why the table is given per parameter family as well.

Exit status: 0 the stated rates are inside the intervals at 2σ and 3σ (1σ is printed, not judged:
with 5–10 seeds per family it is too noisy); 1 otherwise; 2 the workflow could not run.
"""

import argparse
import json
import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from metrocell_contract import ContractError, parameter_entries  # noqa: E402
from score_robot_suite import WorkflowError, load_json, run  # noqa: E402
from truth_matching import match  # noqa: E402

NORMAL_RATE = {1: 0.6827, 2: 0.9545, 3: 0.9973}


def wilson(k, n, z=1.96):
    """The 95 % Wilson score interval of a binomial fraction k/n."""
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return (max(0.0, c - h), min(1.0, c + h))


def seed_z(a, seed, entry, work):
    """The judged parameters of one seed's flat-floor calibration: [(term, name, z)]."""
    os.makedirs(work, exist_ok=True)
    sd = os.path.join(a.suite, f"seed_{seed}", a.calibration)
    bag = os.path.join(work, "bag")
    run([a.metrocell, "bag", "import", os.path.join(sd, "export.csv"), "--mapping", os.path.join(sd, "mapping.yaml"), "-o", bag], a.timeout)
    fit_json = os.path.join(work, "fit.json")
    model = os.path.join(a.suite, f"seed_{seed}", a.calibrate_model)
    run([a.metrocell, "calibrate", "--model", model, bag, "-o", os.path.join(work, "fitted.yaml"), "--json", fit_json], a.timeout)
    rows = match(parameter_entries(load_json(fit_json, f"calibrate seed {seed}")), entry["robot"])
    return [(r["term"], r["name"], r["z"]) for r in rows if r["judged"] and r.get("z") is not None]


def coverage_table(zs):
    """{family: {k: (inside, n, (lo, hi))}} for k = 1, 2, 3 σ, families and 'all'."""
    families = sorted({t for t, _, _ in zs}) + ["all"]
    out = {}
    for fam in families:
        sel = [abs(z) for t, _, z in zs if fam in ("all", t)]
        out[fam] = {k: (sum(z <= k for z in sel), len(sel), wilson(sum(z <= k for z in sel), len(sel))) for k in (1, 2, 3)}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--metrocell", required=True)
    ap.add_argument("--suite", required=True)
    ap.add_argument("--seeds", nargs="*")
    ap.add_argument("--calibrate-model", default="model_gravity.yaml")
    ap.add_argument("--out")
    ap.add_argument("--timeout", type=float, default=900.0)
    a = ap.parse_args()
    with open(os.path.join(a.suite, "answers.json")) as f:
        answers = json.load(f)
    a.calibration = answers["calibration_condition"]
    seeds = a.seeds or sorted(answers["seeds"], key=int)
    zs, per_seed = [], {}
    with tempfile.TemporaryDirectory(prefix="robot_coverage_") as work:
        for seed in seeds:
            try:
                got = seed_z(a, seed, answers["seeds"][str(seed)], os.path.join(work, f"seed_{seed}"))
            except (WorkflowError, ContractError) as e:
                print(f"seed {seed}: the workflow could not run: {e}", file=sys.stderr)
                return 2
            per_seed[seed] = got
            zs.extend(got)
            print(f"seed {seed}: " + ", ".join(f"{t}[{n}] {z:+.2f}" for t, n, z in got), flush=True)
    table = coverage_table(zs)
    ok = True
    print(f"\ncoverage of the stated σ over {len(seeds)} independent robots (fraction with |fitted − truth| ≤ kσ; 95 % interval)")
    print(f"{'family':18s} {'n':>4s}  " + "  ".join(f"{'≤' + str(k) + 'σ':>22s}" for k in (1, 2, 3)))
    for fam, row in table.items():
        cells = []
        for k in (1, 2, 3):
            inside, n, (lo, hi) = row[k]
            covered = lo <= NORMAL_RATE[k] <= hi or inside == n
            if fam == "all" and k > 1 and not covered:
                ok = False
            cells.append(f"{inside / n:6.1%} [{lo:5.1%},{hi:6.1%}]{' ' if covered else '!'}")
        print(f"{fam:18s} {row[1][1]:4d}  " + "  ".join(f"{c:>22s}" for c in cells))
    print("stated rates: 68.3 %, 95.4 %, 99.7 %; '!' marks a family whose interval excludes the stated rate")
    if a.out:
        with open(a.out, "w") as f:
            json.dump({"per_seed": {str(s): [list(r) for r in v] for s, v in per_seed.items()},
                       "coverage": {fam: {str(k): {"inside": v[0], "n": v[1], "interval95": v[2]} for k, v in row.items()} for fam, row in table.items()},
                       "stated_rates_covered": ok}, f, indent=1)
    print("\n" + ("the stated σ cover the truth at their stated rate (2σ and 3σ, all parameters)" if ok else "COVERAGE FAILS: the stated σ do not cover the truth at their stated rate"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
