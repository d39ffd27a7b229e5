#!/usr/bin/env python3
"""Score `metrocell diagnose` on the independent suite (generate_suite.py) against its answer key.

    python3 bags/independent/score_suite.py --metrocell PATH --suite DIR [--out results.json]
        [--workers 2] [--require-targets] [--keep-bags]

For every recording: `metrocell bag import export.csv --mapping mapping.yaml -o BAG`, then
`metrocell diagnose --model model.yaml BAG --json -` (two at a time at most), judged with only the
JSON contract of crates/diagnose/README.md:

  (a) single: the concealed term (id and label) is findings[0]; an instrument drift (the tracker's
      stand sinking or turning) counts as correct when named `instrument_drift` or, with no
      physical finding, reported in `unexplained`;
  (b) pair: both among findings;
  (c) null: findings empty; out-of-catalog: findings empty and an `unexplained` entry;
      confounder: the leader or its `alternatives` hold the truth (or, nothing physical claimed,
      an `unexplained` entry); below-noise: no term other than the concealed one claimed;
  (d) every reported parameter of a correctly named term within 3σ of the truth (translated into
      the catalog's parameters, catalog_translation.py); unidentifiable ones are not judged;
  (e) after.heldout_rms_m ≤ 1.2 × noise_rms_m where the terms were found.

Then `metrocell calibrate` on the sign-reversed reversal case with backlash[y] declared free: the
reversal must come back negative, within 3σ of the truth; parameters at a bound must be named.
Exits non-zero with --require-targets when a target is missed.
"""

import argparse
import concurrent.futures as cf
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

TARGETS = {  # category -> (what, minimum rate)
    "single": ("concealed term named first", 0.95),
    "sign_reversed": ("concealed term named first", 0.95),
    "range_3x": ("concealed term named first", 0.95),
    "half_magnitude": ("concealed term named first", 0.85),
    "pair": ("both terms found", 0.85),
    "null": ("no physical term claimed", 1.0),
    "out_of_catalog": ("nothing physical claimed, unexplained reported", 1.0),
    "confounder": ("truth is the leader or among its alternatives", 0.95),
    "below_noise": ("no wrong term claimed", 1.0),
}
CATEGORY_ORDER = list(TARGETS)
PARAM_TARGET, RMS_TARGET = 0.95, 0.95


def run(cmd, timeout):
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    return p, time.time() - t0


def diagnose_one(metrocell, rec_dir, work_dir, timeout):
    bag = os.path.join(work_dir, "bag")
    shutil.rmtree(bag, ignore_errors=True)
    p, t_imp = run([metrocell, "bag", "import", os.path.join(rec_dir, "export.csv"), "--mapping",
                    os.path.join(rec_dir, "mapping.yaml"), "-o", bag], timeout)
    if p.returncode != 0:
        return {"error": f"bag import failed ({p.returncode}): {p.stderr.strip()[-2000:]}", "import_s": t_imp}
    try:
        p, t_diag = run([metrocell, "diagnose", "--model", os.path.join(rec_dir, "model.yaml"), bag, "--json", "-"], timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"diagnose timed out after {timeout} s", "import_s": t_imp, "bag": bag}
    if p.returncode != 0:
        return {"error": f"diagnose failed ({p.returncode}): {p.stderr.strip()[-2000:]}", "import_s": t_imp, "bag": bag}
    try:
        j = json.loads(p.stdout[p.stdout.index("{"):])
    except (ValueError, json.JSONDecodeError) as e:
        return {"error": f"diagnose JSON unreadable: {e}", "bag": bag}
    return {"json": j, "import_s": t_imp, "diagnose_s": t_diag, "bag": bag}


# -- judging ----------------------------------------------------------------------------------------

def _named(finding, expected):
    return finding.get("term") == expected["term"] and finding.get("label") == expected["label"]


def _is_instrument_drift(expected):
    return expected.get("unexplained_is_correct", False)


def _direction_sign(finding):
    """The direction n̂ a thermal_growth finding's coefficient is along, from its variant
    ("along z" → +1, "along −z" → −1); None when the variant does not say. (The statement
    says which way the tool moves, which is n̂ times the coefficient's sign: not used.)"""
    variant = str(finding.get("variant", ""))
    if "along −z" in variant or "along -z" in variant:
        return -1.0
    if "along z" in variant or "along +z" in variant:
        return 1.0
    return None


def judge_parameters(finding, expected):
    """Each reported parameter against the translated truth: [{name, value, sigma, truth, z, ok}]."""
    out = []
    truth_params = expected["parameters"]
    by_alias = {}
    for name, spec in truth_params.items():
        by_alias[name.lower()] = name
        for al in spec.get("aliases", []):
            by_alias[al.lower()] = name
    degenerate = expected.get("degenerate", [])
    reported = finding.get("parameters", {}) or {}
    for name, rep in reported.items():
        key = by_alias.get(name.lower())
        value, sigma = rep.get("value"), rep.get("sigma")
        if key is None:
            out.append({"name": name, "value": value, "sigma": sigma, "truth": None, "judged": False, "why": "no translated truth"})
            continue
        spec = truth_params[key]
        if not spec["identifiable"]:
            out.append({"name": name, "value": value, "sigma": sigma, "truth": spec["value"], "judged": False, "why": "not identifiable"})
            continue
        if degenerate and len([k for k in reported if by_alias.get(k.lower()) in degenerate]) > 1:
            out.append({"name": name, "value": value, "sigma": sigma, "truth": spec["value"], "judged": False,
                        "why": "degenerate pair reported together"})
            continue
        truth = spec["value"]
        if expected["term"] == "thermal_growth" and key == "coefficient":
            sign = _direction_sign(finding)
            truth = truth * (sign if sign is not None else 1.0)
        ok = (value is not None and sigma is not None and math.isfinite(value) and sigma > 0
              and abs(value - truth) <= 3.0 * sigma)
        z = (value - truth) / sigma if (value is not None and sigma) else None
        out.append({"name": name, "value": value, "sigma": sigma, "truth": truth, "z": z, "judged": True, "ok": bool(ok)})
    return out


def judge(entry, seed_entry, j):
    kind, category = entry["kind"], entry["category"]
    findings = j.get("findings") or []
    unexplained = j.get("unexplained") or []
    expected = [e for eff in seed_entry["effects"] for e in eff["expected"]]
    verdict = {"named": False, "params": [], "rms_ok": None}
    lead = findings[0] if findings else None
    if kind == "single" and category == "below_noise":
        verdict["named"] = all(_named(f, expected[0]) for f in findings)
    elif kind == "single":
        exp = expected[0]
        if lead is not None and _named(lead, exp):
            verdict["named"] = True
        elif _is_instrument_drift(exp) and not findings and unexplained:
            verdict["named"] = True
            verdict["named_as"] = "unexplained"
    elif kind == "pair":
        verdict["named"] = all(any(_named(f, e) for f in findings) for e in expected)
    elif kind == "null":
        verdict["named"] = not findings
    elif kind == "out_of_catalog":
        verdict["named"] = not findings and bool(unexplained)
    elif kind == "confounder":
        exp = expected[0]
        if lead is not None:
            alts = lead.get("alternatives") or []
            verdict["named"] = _named(lead, exp) or any(a.get("term") == exp["term"] for a in alts)
        else:
            verdict["named"] = bool(unexplained)
    # parameters of the correctly named terms
    if verdict["named"] and kind in ("single", "pair", "confounder"):
        for e in expected:
            for f in findings:
                if _named(f, e):
                    verdict["params"] += [{**p, "term": e["label"]} for p in judge_parameters(f, e)]
    found_terms = verdict["named"] and kind in ("single", "pair") and category != "below_noise" and bool(findings)
    if found_terms:
        after, noise = (j.get("after") or {}).get("heldout_rms_m"), j.get("noise_rms_m")
        verdict["rms_ok"] = after is not None and noise is not None and after <= 1.2 * noise
        verdict["rms_ratio"] = after / noise if after is not None and noise else None
    return verdict


def summary_of_miss(entry, seed_entry, j):
    findings = j.get("findings") or []
    lead = findings[0] if findings else None
    selection = j.get("selection") or []
    steps = []
    for step in selection[:3]:
        steps.append({"chosen": step.get("chosen"),
                      "top": [{k: c.get(k) for k in ("label", "variant", "heldout_gain", "p_adjusted", "delta_bic", "plausible", "separable", "accepted")}
                              for c in (step.get("top") or [])[:5]]})
    return {
        "truth": [{"effect": e["effect"], "expected": [x["label"] for x in e["expected"]], "truth": e["truth"]} for e in seed_entry["effects"]],
        "findings0": None if lead is None else {"term": lead.get("term"), "label": lead.get("label"), "variant": lead.get("variant"),
                                               "parameters": lead.get("parameters"), "statement": lead.get("statement"),
                                               "alternatives": lead.get("alternatives")},
        "other_findings": [f.get("label") for f in findings[1:]],
        "unexplained": [u.get("statement") for u in (j.get("unexplained") or [])],
        "selection": steps,
        "not_tried": j.get("not_tried"),
        "noise": j.get("noise"), "before": j.get("before"), "after": j.get("after"), "noise_rms_m": j.get("noise_rms_m"),
    }


# -- calibrate ------------------------------------------------------------------------------------

def _find_parameter(obj, label, name, path=""):
    """Search calibrate's JSON for the parameter `label`.`name`: [(path, dict)]."""
    hits = []
    if isinstance(obj, dict):
        for k, v in obj.items():
            p = f"{path}/{k}"
            if isinstance(v, dict) and (k in (f"{label}.{name}", f"{label}/{name}") or
                                        (label in p and k == name)):
                hits.append((p, v))
            hits += _find_parameter(v, label, name, p)
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            if isinstance(v, dict) and (v.get("name") == f"{label}.{name}" or
                                        (v.get("label") == label and name in (v.get("name"), v.get("parameter")))):
                hits.append((f"{path}[{i}]", v))
            hits += _find_parameter(v, label, name, f"{path}[{i}]")
    return hits


def _find_key(obj, key, path=""):
    hits = []
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k == key:
                hits.append((f"{path}/{k}", v))
            hits += _find_key(v, key, f"{path}/{k}")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            hits += _find_key(v, key, f"{path}[{i}]")
    return hits


def calibrate_check(metrocell, rec_dir, bag, truth_reversal, timeout):
    out_json = os.path.join(os.path.dirname(bag), "calibrate.json")
    fitted = os.path.join(os.path.dirname(bag), "fitted.yaml")
    p, secs = run([metrocell, "calibrate", "--model", os.path.join(rec_dir, "model_backlash_free.yaml"), bag,
                   "--json", out_json, "-o", fitted], timeout)
    res = {"returncode": p.returncode, "seconds": secs, "truth_reversal_m": truth_reversal}
    if p.returncode != 0:
        res["error"] = p.stderr.strip()[-2000:]
        return res
    with open(out_json) as f:
        j = json.load(f)
    hits = _find_parameter(j, "backlash[y]", "reversal")
    bounds = _find_key(j, "at_bound")
    res["at_bound_field_present"] = bool(bounds)
    # what is reported at a bound: every non-empty at_bound (per parameter or a list)
    res["at_bound"] = [{"path": pth, "value": v} for pth, v in bounds if v not in (None, [], False)]
    if not hits:
        res["error"] = "backlash[y].reversal not found in calibrate's JSON"
        res["json_keys"] = list(j)[:30]
        return res
    path, par = hits[0]
    value, sigma = par.get("value"), par.get("sigma", par.get("uncertainty"))
    res.update({"path": path, "value": value, "sigma": sigma, "parameter_entry": par,
                "not_identifiable": j.get("not_identifiable")})
    res["negative"] = value is not None and value < 0
    res["within_3sigma"] = value is not None and sigma is not None and abs(value - truth_reversal) <= 3 * sigma
    return res


# -- main -----------------------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--metrocell", required=True)
    ap.add_argument("--suite", required=True)
    ap.add_argument("--out")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=1800.0)
    ap.add_argument("--require-targets", action="store_true")
    ap.add_argument("--keep-bags", action="store_true")
    a = ap.parse_args()
    workers = max(1, min(a.workers, 2))
    with open(os.path.join(a.suite, "answers.json")) as f:
        answers = json.load(f)
    work_root = tempfile.mkdtemp(prefix="indep_score_")
    jobs = []
    for case, entry in sorted(answers["cases"].items()):
        for seed in sorted(entry["seeds"], key=int):
            jobs.append((case, seed))
    t0 = time.time()
    results = {}
    with cf.ThreadPoolExecutor(max_workers=workers) as pool:
        futs = {}
        for case, seed in jobs:
            rec = os.path.join(a.suite, case, f"seed_{seed}")
            wd = os.path.join(work_root, case, f"seed_{seed}")
            os.makedirs(wd, exist_ok=True)
            futs[pool.submit(diagnose_one, a.metrocell, rec, wd, a.timeout)] = (case, seed)
        for fut in cf.as_completed(futs):
            case, seed = futs[fut]
            results[(case, seed)] = fut.result()
            r = results[(case, seed)]
            entry = answers["cases"][case]
            status = "ERROR " + r["error"][:200] if "error" in r else \
                f"findings: {[x.get('label') for x in r['json'].get('findings') or []]} ({r['diagnose_s']:.0f} s)"
            print(f"  {case} seed {seed} {entry['key']:36s} {status}", flush=True)
    wall = time.time() - t0
    # judge
    per_run, misses = [], []
    for (case, seed), r in sorted(results.items()):
        entry = answers["cases"][case]
        seed_entry = entry["seeds"][seed]
        row = {"case": case, "seed": int(seed), "key": entry["key"], "kind": entry["kind"], "category": entry["category"],
               "peak_in_noise": seed_entry.get("effect_peak_in_noise")}
        if "error" in r:
            row.update({"error": r["error"], "named": False})
            misses.append({**row})
        else:
            j = r["json"]
            v = judge(entry, seed_entry, j)
            row.update(v)
            row["findings"] = [f.get("label") for f in j.get("findings") or []]
            row["unexplained"] = len(j.get("unexplained") or [])
            row["diagnose_s"] = r.get("diagnose_s")
            row["noise_rms_m"], row["after_heldout_rms_m"] = j.get("noise_rms_m"), (j.get("after") or {}).get("heldout_rms_m")
            bad_params = [p for p in v["params"] if p.get("judged") and not p.get("ok")]
            if not v["named"] or bad_params or v.get("rms_ok") is False:
                misses.append({**row, "why": ("not named" if not v["named"] else "") + (" parameters" if bad_params else "") +
                               (" rms" if v.get("rms_ok") is False else ""), **summary_of_miss(entry, seed_entry, j)})
        per_run.append(row)
    # the table
    print()
    print(f"{'category':16s} {'runs':>5s} {'correct':>8s} {'rate':>6s} {'target':>7s}   {'params ok':>10s} {'rms ok':>8s}")
    table, all_ok = {}, True
    p_ok = p_n = r_ok = r_n = 0
    for cat in CATEGORY_ORDER:
        rows = [r for r in per_run if r["category"] == cat]
        if not rows:
            continue
        n = len(rows)
        c = sum(1 for r in rows if r.get("named"))
        pj = [p for r in rows for p in r.get("params", []) if p.get("judged")]
        pk = sum(1 for p in pj if p.get("ok"))
        rj = [r for r in rows if r.get("rms_ok") is not None]
        rk = sum(1 for r in rj if r["rms_ok"])
        p_ok, p_n, r_ok, r_n = p_ok + pk, p_n + len(pj), r_ok + rk, r_n + len(rj)
        what, target = TARGETS[cat]
        met = c / n >= target - 1e-12
        all_ok &= met
        table[cat] = {"runs": n, "correct": c, "rate": c / n, "target": target, "what": what, "met": met,
                      "params_ok": pk, "params_judged": len(pj), "rms_ok": rk, "rms_judged": len(rj)}
        print(f"{cat:16s} {n:5d} {c:8d} {c / n:6.0%} {target:7.0%}{'' if met else ' MISS'}   {pk:4d}/{len(pj):<5d} {rk:4d}/{len(rj):<3d}")
    param_rate = p_ok / p_n if p_n else 1.0
    rms_rate = r_ok / r_n if r_n else 1.0
    print(f"parameters within 3 sigma: {p_ok}/{p_n} = {param_rate:.0%} (target {PARAM_TARGET:.0%})"
          f"{'' if param_rate >= PARAM_TARGET else ' MISS'}")
    print(f"held-out RMS <= 1.2 x noise where found: {r_ok}/{r_n} = {rms_rate:.0%} (target {RMS_TARGET:.0%})"
          f"{'' if rms_rate >= RMS_TARGET else ' MISS'}")
    all_ok &= param_rate >= PARAM_TARGET and rms_rate >= RMS_TARGET
    # calibrate on the sign-reversed reversal case
    calib = []
    for (case, seed), r in sorted(results.items()):
        entry = answers["cases"][case]
        if entry["key"] != "reversal_y_overcompensated" or "bag" not in r:
            continue
        truth = entry["seeds"][seed]["effects"][0]["expected"][0]["parameters"]["reversal"]["value"]
        c = calibrate_check(a.metrocell, os.path.join(a.suite, case, f"seed_{seed}"), r["bag"], truth, a.timeout)
        c.update({"case": case, "seed": int(seed)})
        calib.append(c)
        ok = c.get("negative") and c.get("within_3sigma")
        all_ok &= bool(ok)
        print(f"calibrate {case} seed {seed}: reversal {c.get('value')} ± {c.get('sigma')} m (truth {truth:.3e}): "
              f"{'negative, within 3 sigma' if ok else 'MISS ' + str(c.get('error', ''))}; "
              f"at_bound {'field present' if c.get('at_bound_field_present') else 'field ABSENT'}, at a bound: {c.get('at_bound')}")
    print(f"\n{len(results)} recordings in {wall:.0f} s with {workers} workers; {len(misses)} with a miss")
    for m in misses:
        print(f"MISS {m['case']} seed {m['seed']} {m['key']} ({m['category']}): {m.get('why', m.get('error'))}; "
              f"findings {m.get('findings')}; unexplained {len(m.get('unexplained') or [])}")
        print(f"     truth: {[t['expected'] for t in m.get('truth', [])]}")
        f0 = m.get("findings0")
        if f0:
            params = {k: f"{v.get('value'):.4g} ± {v.get('sigma'):.2g}" for k, v in (f0.get("parameters") or {}).items()}
            print(f"     findings[0]: {f0.get('label')} ({f0.get('variant')}) {params}; alternatives {f0.get('alternatives')}")
        bad = [p for p in m.get("params", []) if p.get("judged") and not p.get("ok")]
        for p in bad:
            print(f"     parameter {p['term']}.{p['name']} = {p['value']:.4g} ± {p['sigma']:.2g}, truth {p['truth']:.4g} (z = {p['z']:+.1f})")
        if m.get("rms_ok") is False:
            print(f"     held-out RMS after / noise = {m.get('rms_ratio'):.2f}")
        for k, step in enumerate((m.get("selection") or [])[:2]):
            tops = ", ".join(f"{c['label']} [{c.get('variant')}] gain {c.get('heldout_gain') or 0:.2f} dBIC {c.get('delta_bic') or 0:.0f}"
                             f" plausible={c.get('plausible')} accepted={c.get('accepted')}" for c in (step.get("top") or [])[:3])
            print(f"     selection step {k + 1} chose {step.get('chosen')}: {tops}")
    if a.out:
        with open(a.out, "w") as f:
            json.dump({"table": table, "parameters": {"ok": p_ok, "judged": p_n, "rate": param_rate},
                       "rms": {"ok": r_ok, "judged": r_n, "rate": rms_rate}, "calibrate": calib,
                       "runs": per_run, "misses": misses, "wall_s": wall, "all_targets_met": all_ok}, f, indent=1, default=str)
    if not a.keep_bags:
        shutil.rmtree(work_root, ignore_errors=True)
    sys.exit(1 if (a.require_targets and not all_ok) else 0)


if __name__ == "__main__":
    main()
