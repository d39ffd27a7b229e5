#!/usr/bin/env python3
"""Baselines beside `metrocell diagnose` on the concealed-effect suite (issue 13).

    .venv/bin/python bags/baselines.py --residuals-dir DIR --seeds 1 2 3 [--cases ...] --out baselines.json \
        [--compare "metrocell diagnose=RESULTS.json" "all at once=RESULTS2.json"]

DIR holds the per-record residual CSVs `metrocell diagnose --residuals` wrote for each case and
seed (`bags/score.py --residuals-dir DIR` writes them as DIR/case_NN_seed_S.csv): per record the
time, the commanded position, the residual after the declared fit with its sigma, and the
signals. Two baselines read them:

* **PySINDy** (`pysindy`, PyPI): sparse regression (SINDy's sequentially thresholded least
  squares, STLSQ) of each residual component on a library of candidate functions built from the
  same signals — per axis Legendre polynomials of the position (positioning, straightness), the
  other axes' positions (squareness), sines and cosines over common ball-screw leads (pitch),
  the approach direction (backlash), position x temperature (thermal scale), temperatures
  (thermal growth, also through first-order lags), velocity (time offset), 1 - exp(-t/tau) of the
  time since power-on (warm-up); a signal some record lacks gives no column.
  The STLSQ threshold is chosen by cross-validation over blocks of time (never random rows).
  A catalog term is "named" when any of its library columns keeps a non-zero coefficient; terms
  are ordered by the size of their fitted contribution.
* **fit everything at once**: ordinary weighted least squares on the whole library; a term is
  named when any of its coefficients is significant at 3 sigma (the classic "fit all, keep
  what is significant").

The `fit every catalog term at once` baseline built on the shared model's own candidate columns
is `metrocell diagnose --strategy ...` itself, scored by score.py; this script's second baseline
is the same idea on SINDy's library, so the two baselines see identical inputs.

Both are judged with score.py's rules (right names, false claims) against the answer key.
"""

import argparse
import csv
import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import score  # noqa: E402  (the same judging rules and answer key)

LEADS_M = [0.005, 0.01, 0.016, 0.02, 0.025, 0.032, 0.04]
WARMUP_TAUS_S = [900.0, 1800.0, 3600.0, 5400.0, 7200.0]
LAG_TAUS_S = [600.0, 1200.0, 2400.0, 4800.0]
AXES = "xyz"


def read_residuals(path):
    """Columns of the residual CSV as numpy arrays (strings kept where not numeric)."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError(f"{path}: no records")
    cols = {}
    for k in rows[0]:
        vals = [r[k] for r in rows]
        try:
            cols[k] = np.array([float(v) if v not in ("", "nan", "NaN") else np.nan for v in vals])
        except ValueError:
            cols[k] = np.array(vals)
    return cols


def find(cols, *names):
    for n in names:
        if n in cols:
            return cols[n]
    return None


def legendre(u, n):
    return np.polynomial.legendre.legval(u, [0] * n + [1])


def library(cols):
    """(features [n x m] per residual component j: list of (name, term, label, column)."""
    t = find(cols, "time", "time_s", "t")
    pos = [find(cols, f"position_{a}", f"q_{a}", f"{a}", f"axis.{a}", f"position.{a}") for a in AXES]
    lib = {j: [] for j in range(3)}
    have_pos = all(p is not None for p in pos)
    if have_pos:
        u = []
        for p in pos:
            lo, hi = np.nanmin(p), np.nanmax(p)
            u.append(2 * (p - lo) / (hi - lo) - 1 if hi > lo else np.zeros_like(p))
        for k, a in enumerate(AXES):
            for n in (1, 2, 3):
                lib[k].append((f"P{n}({a})", "positioning", f"positioning[{a}]", legendre(u[k], n)))
            for j, b in enumerate(AXES):
                if j == k:
                    continue
                for n in (2, 3):
                    lib[j].append((f"P{n}({a})", "straightness", f"straightness[{a}:{b}]", legendre(u[k], n)))
            for lead in LEADS_M:
                w = 2 * math.pi * pos[k] / lead
                lib[k].append((f"cos(2pi {a}/{lead * 1e3:g}mm)", "pitch_cyclic", f"pitch_cyclic[{a}]", np.cos(w)))
                lib[k].append((f"sin(2pi {a}/{lead * 1e3:g}mm)", "pitch_cyclic", f"pitch_cyclic[{a}]", np.sin(w)))
        # squareness: xy → dx ∝ y, xz → dx ∝ z, yz → dy ∝ z
        lib[0].append(("y", "squareness", "squareness[xy]", pos[1]))
        lib[0].append(("z", "squareness", "squareness[xz]", pos[2]))
        lib[1].append(("z", "squareness", "squareness[yz]", pos[2]))
    for k, a in enumerate(AXES):
        s = find(cols, f"approach_{a}", f"approach.{a}")
        if s is not None:
            lib[k].append((f"s_{a}", "backlash", f"backlash[{a}]", s))
        v = find(cols, f"velocity_{a}", f"velocity.{a}")
        if v is not None:
            lib[k].append((f"v_{a}", "time_offset", "time_offset", v))
    temps = {k.split(".", 1)[1] if "." in k else k[len("temperature_"):]: v for k, v in cols.items()
             if (k.startswith("temperature.") or k.startswith("temperature_")) and v.dtype.kind == "f"}
    for name, temp in temps.items():
        dT = temp - 20.0
        if have_pos:
            for k, a in enumerate(AXES):
                lib[k].append((f"{a}*(T_{name}-20)", "thermal_scale", f"thermal_scale[{a}]", pos[k] * dT))
        for j in range(3):
            lib[j].append((f"T_{name}-20", "thermal_growth", f"thermal_growth[{name}]", dT))
            if t is not None:
                for tau in LAG_TAUS_S:
                    lib[j].append((f"lag{tau / 60:g}min(T_{name})-20", "thermal_growth", f"thermal_growth[{name}]", first_order_lag(t, temp, tau) - 20.0))
    on = find(cols, "time_since_power_on", "power_on_s")
    if on is not None and np.all(np.isfinite(on)):
        for tau in WARMUP_TAUS_S:
            for j in range(3):
                lib[j].append((f"1-exp(-t_on/{tau:g}s)", "tracker_warmup", "tracker_warmup", 1 - np.exp(-on / tau)))
    # a signal some record lacks (an empty cell) is no library column
    return t, {j: [f for f in feats if np.all(np.isfinite(f[3]))] for j, feats in lib.items()}


def first_order_lag(t, temp, tau):
    """The temperatures through a first-order lag of time constant tau, over the records' own
    (irregular) times: the exact response to a piecewise-constant input."""
    order = np.argsort(t)
    out = np.empty_like(temp)
    y = temp[order[0]]
    prev = t[order[0]]
    for i in order:
        y += (1 - np.exp(-(t[i] - prev) / tau)) * (temp[i] - y)
        out[i], prev = y, t[i]
    return out


def residual_components(cols):
    r = [find(cols, f"residual_{a}", f"r_{a}", f"residual.{a}") for a in AXES]
    s = [find(cols, f"sigma_{a}", f"sigma.{a}", "sigma") for a in AXES]
    if any(v is None for v in r) or any(v is None for v in s):
        raise ValueError(f"residual CSV lacks residual/sigma columns: {sorted(cols)}")
    return r, s


def blocked_folds(t, k=5):
    order = np.argsort(t)
    return [np.sort(b) for b in np.array_split(order, k)]


def stlsq_fit(X, y, threshold):
    import warnings

    import pysindy as ps

    warnings.filterwarnings("ignore", message="Sparsity parameter is too big")

    model = ps.SINDy(optimizer=ps.STLSQ(threshold=threshold, alpha=1e-6, normalize_columns=False), feature_library=ps.IdentityLibrary())
    model.fit(X, t=1.0, x_dot=y.reshape(-1, 1))
    return np.asarray(model.coefficients()).ravel()


def sindy_terms(t, lib, r, s):
    """{label: (term, contribution RMS)} named by PySINDy."""
    named = {}
    for j in range(3):
        feats = lib[j]
        if not feats:
            continue
        w = 1.0 / s[j]
        X = np.column_stack([f[3] for f in feats]) * w[:, None]
        y = r[j] * w
        ok = np.all(np.isfinite(X), axis=1) & np.isfinite(y)
        X, y, tt = X[ok], y[ok], t[ok]
        X = X - X.mean(axis=0)          # the declared fit already removed offsets
        scale = X.std(axis=0)
        scale[scale == 0] = 1.0
        Xs = X / scale
        # threshold by blocked cross-validation over a grid (whitened units per unit-variance
        # feature), with the one-standard-error rule: the sparsest model whose held-out error
        # is within one standard error of the best (the usual guard against overfitting)
        grid = np.geomspace(3e-3, 3.0, 12)
        folds = blocked_folds(tt)
        errs = np.zeros((len(grid), len(folds)))
        for gi, th in enumerate(grid):
            for fi, f in enumerate(folds):
                train = np.setdiff1d(np.arange(len(y)), f)
                c = stlsq_fit(Xs[train], y[train] - y[train].mean(), th)
                errs[gi, fi] = np.mean((y[f] - y[train].mean() - Xs[f] @ c) ** 2)
        mean, se = errs.mean(axis=1), errs.std(axis=1, ddof=1) / np.sqrt(len(folds))
        i_min = int(np.argmin(mean))
        best = grid[max(i for i in range(len(grid)) if mean[i] <= mean[i_min] + se[i_min])]
        c = stlsq_fit(Xs, y - y.mean(), best)
        for (name, term, label, _), coef, col in zip(feats, c, Xs.T):
            if coef != 0.0:
                contrib = float(np.sqrt(np.mean((coef * col / w[ok]) ** 2)))
                named[label] = (term, named.get(label, (term, 0.0))[1] + contrib)
    return named


def ols_terms(t, lib, r, s):
    """{label: (term, contribution RMS)} significant at 3 sigma in one weighted fit of everything."""
    named = {}
    for j in range(3):
        feats = lib[j]
        if not feats:
            continue
        w = 1.0 / s[j]
        X = np.column_stack([np.ones_like(r[j])] + [f[3] for f in feats]) * w[:, None]
        y = r[j] * w
        ok = np.all(np.isfinite(X), axis=1) & np.isfinite(y)
        X, y = X[ok], y[ok]
        coef, *_ = np.linalg.lstsq(X, y, rcond=None)
        dof = max(len(y) - np.linalg.matrix_rank(X), 1)
        s2 = float(np.sum((y - X @ coef) ** 2) / dof)
        cov = s2 * np.linalg.pinv(X.T @ X)
        se = np.sqrt(np.maximum(np.diag(cov), 0))
        for (name, term, label, _), b, e, col in zip(feats, coef[1:], se[1:], X[:, 1:].T):
            if e > 0 and abs(b) > 3 * e:
                contrib = float(np.sqrt(np.mean((b * col / w[ok]) ** 2)))
                named[label] = (term, named.get(label, (term, 0.0))[1] + contrib)
    return named


def as_result(named):
    """A diagnose-like JSON result (findings ordered by contribution) for score.judge."""
    findings = [{"term": term, "label": label, "parameters": {}} for label, (term, _) in sorted(named.items(), key=lambda kv: -kv[1][1])]
    return {"findings": findings, "unexplained": [], "noise_rms_m": None, "after": {}, "before": {}}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--residuals-dir", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--cases", nargs="*")
    ap.add_argument("--out", required=True)
    ap.add_argument("--compare", nargs="*", default=[], metavar="NAME=RESULTS.json",
                    help="score.py results to put in the side-by-side table (e.g. 'metrocell diagnose=/tmp/m.json')")
    a = ap.parse_args(argv)
    answers = score.load_answers()
    cases = a.cases or sorted(answers)
    out = {"pysindy": [], "library_ols": []}
    for case in cases:
        for seed in a.seeds:
            path = os.path.join(a.residuals_dir, f"{case}_seed_{seed}.csv")
            cols = read_residuals(path)
            t, lib = library(cols)
            r, s = residual_components(cols)
            for name, fn in (("pysindy", sindy_terms), ("library_ols", ols_terms)):
                v = score.judge(answers[case], as_result(fn(t, lib, r, s)))
                out[name].append({"case": case, "seed": seed, "verdict": v})
                print(f"{name:12s} {case} seed {seed} ({answers[case]['kind']}): {'ok ' if v['ok'] else 'MISS'} {v['named']}", flush=True)
    summary = {name: score.aggregate([x["verdict"] for x in runs]) for name, runs in out.items()}
    with open(a.out, "w") as f:
        json.dump({"summary": summary, "runs": out}, f, indent=1)
    rows = {}
    for spec in a.compare:
        name, path = spec.split("=", 1)
        with open(path) as f:
            rows[name] = json.load(f)["summary"]
    rows.update({"PySINDy (STLSQ, same signals)": summary["pysindy"], "fit everything, library OLS at 3σ": summary["library_ols"]})
    print(side_by_side(rows))
    return 0


def side_by_side(rows):
    """Markdown table of methods: naming rates and false claims (score.aggregate summaries)."""
    def frac(t):
        n, total = t[0], t[1]
        return f"{n}/{total} ({100 * n / total:.0f} %)" if total else "—"

    lines = ["| method | right term first (single) | both found (two) | right physics named (all concealed terms) | null runs clean | out-of-catalog runs clean | false claims (terms not concealed) | runs with a false claim |",
             "|---|---|---|---|---|---|---|---|"]
    for name, sm in rows.items():
        fc, runs = sm["false_claims"][0], sm["false_claims"][1]
        lines.append(f"| {name} | {frac(sm['single_first'])} | {frac(sm['two_both'])} | {frac(sm['right_names'])} | {frac(sm['null_clean'])} | "
                     f"{frac(sm['out_of_catalog_clean'])} | {fc} in {runs} runs | {frac(sm['runs_with_false_claims'])} |")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
