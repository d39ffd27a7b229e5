#!/usr/bin/env python3
"""Tracker-style CSV exports made with numpy only — not by metrocell's twin.

    python3 bags/independent/make_exports.py --out DIR [--seed N]

Writes DIR/<variant>.csv for each variant below, plus DIR/truth.json (what each export
conceals; read by the test, never by metrocell). Import with
`metrocell bag import DIR/<variant>.csv --mapping bags/independent/mapping.yaml -o BAG` and
diagnose with `--model bags/independent/model.yaml`.

Everything here is deliberately unlike the twin (so a method that leans on the twin's habits
fails here):
  * own column names and units: millimetres, U95 (k = 2) per point, "Dir X"/"Dir Y" approach
    flags, temperatures of a bed sensor and of the air in their own columns, time in seconds
    since the job started;
  * own sampling: points drawn uniformly at random inside the working volume (no grid), each
    round of the job visiting them in a new random order, rounds at irregular intervals;
  * own noise: isotropic Gaussian with a per-point sigma that grows with the distance from the
    instrument, sigma = U95/2, U95 = 6 um + 4 um/m * distance; heavy-tailed (Student t, 5 dof,
    scaled to the same sigma) in one variant;
  * own thermal history: the bed warms along a logistic curve with a slow ripple; the air
    follows a different curve;
  * the points are already in the machine frame (the export's software aligned the
    instrument on reference nests of the bed, independently of the measured errors).

Variants (the concealed effect, SI; equations in the catalog's conventions, crates/physics):
  scale:     X scale grows with the bed temperature, dx = alpha*x*(T_bed - 20 degC),
             alpha = 12.5e-6 1/K (peak ~40 um at 0.8 m and 24 degC)
  reversal:  a reversal error on Y, dy = -(beta/2)*s_y, beta = 14 um, s_y = the sign of the last
             Y motion before the point ("Dir Y")
  null:      nothing: measured = nominal + noise
  null_t:    nothing, heavy-tailed noise (Student t, 5 degrees of freedom)
"""

import argparse
import csv
import json
import os

import numpy as np

TRAVEL_MM = np.array([800.0, 500.0, 400.0])
INSTRUMENT_MM = np.array([-900.0, 250.0, 650.0])   # where the instrument stood (machine frame)
ALPHA = 12.5e-6
BETA = 14e-6

VARIANTS = {
    "scale": {"effect": "thermal_scale", "label": "thermal_scale[x]", "parameters": {"alpha": ALPHA}},
    "reversal": {"effect": "backlash", "label": "backlash[y]", "parameters": {"reversal": BETA}},
    "null": {"effect": None},
    "null_t": {"effect": None, "noise": "student_t5"},
}


def temperatures(t_s, rng):
    """Bed and air temperature (degC) at job times t (s): logistic warm-up plus a ripple."""
    h = t_s / 3600.0
    bed = 20.6 + 3.4 / (1.0 + np.exp(-(h - 2.2) * 1.6)) + 0.15 * np.sin(2 * np.pi * h / 1.7)
    air = 20.9 + 0.35 * h - 0.04 * h * h + 0.1 * np.cos(2 * np.pi * h / 2.9)
    return bed + rng.normal(0, 0.01, t_s.shape), air + rng.normal(0, 0.02, t_s.shape)


def job(rng, n_points=40, rounds=7):
    """Nominal points (mm), visiting order per round, times (s)."""
    nominal = rng.uniform([0, 0, 0], TRAVEL_MM, size=(n_points, 3)).round(1)
    rows, t = [], 0.0
    for r in range(rounds):
        t = r * 3000.0 + rng.uniform(0, 600)        # rounds roughly every 50 min, irregular
        for i in rng.permutation(n_points):
            t += rng.uniform(6.0, 11.0)                # move + settle + measure
            rows.append((r, int(i), t))
    return nominal, rows


def approach_flags(nominal, rows):
    """Sign of the last non-zero motion of each axis before each point (+1 at the start)."""
    last = np.ones(3)
    prev = np.array([0.0, 0.0, TRAVEL_MM[2]])      # the job starts at home
    out = []
    for _, i, _ in rows:
        step = nominal[i] - prev
        last = np.where(step != 0, np.sign(step), last)
        out.append(last.copy())
        prev = nominal[i]
    return np.array(out)


def export(variant, spec, seed, out_dir):
    rng = np.random.default_rng(seed * 1009 + sum(map(ord, variant)))
    nominal, rows = job(rng)
    idx = np.array([i for _, i, _ in rows])
    t = np.array([tt for _, _, tt in rows])
    nom = nominal[idx] / 1000.0                              # m
    bed, air = temperatures(t, rng)
    approach = approach_flags(nominal, rows)
    d = np.zeros_like(nom)
    if spec["effect"] == "thermal_scale":
        d[:, 0] = ALPHA * nom[:, 0] * (bed - 20.0)
    elif spec["effect"] == "backlash":
        d[:, 1] = -(BETA / 2.0) * approach[:, 1]
    distance = np.linalg.norm(nominal[idx] - INSTRUMENT_MM, axis=1) / 1000.0
    u95 = 6e-6 + 4e-6 * distance                             # m, k = 2
    sigma = u95 / 2.0
    if spec.get("noise") == "student_t5":
        z = rng.standard_t(5, size=nom.shape) / np.sqrt(5.0 / 3.0)   # unit variance
    else:
        z = rng.normal(size=nom.shape)
    measured = nom + d + z * sigma[:, None]
    path = os.path.join(out_dir, f"{variant}.csv")
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["PointID", "Round", "Time [s]", "Xnom [mm]", "Ynom [mm]", "Znom [mm]", "X [mm]", "Y [mm]", "Z [mm]",
                    "U95 [mm]", "T_bed [C]", "T_air [C]", "Dir X", "Dir Y", "Dir Z"])
        for k, (r, i, _) in enumerate(rows):
            w.writerow([f"N{i + 1:03d}", r + 1, f"{t[k]:.2f}", *(f"{v:.1f}" for v in nominal[i]),
                        *(f"{v * 1000:.5f}" for v in measured[k]), f"{u95[k] * 1000:.5f}", f"{bed[k]:.3f}", f"{air[k]:.3f}",
                        *(f"{int(a):+d}" for a in approach[k])])
    return len(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--variants", nargs="*", default=sorted(VARIANTS))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    truth = {}
    for v in a.variants:
        n = export(v, VARIANTS[v], a.seed, a.out)
        truth[v] = {**VARIANTS[v], "rows": n, "seed": a.seed}
    with open(os.path.join(a.out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1, sort_keys=True)
    print(f"wrote {len(truth)} exports to {a.out}")


if __name__ == "__main__":
    main()
