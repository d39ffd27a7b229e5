#!/usr/bin/env python3
"""Write the independent concealed-effect suite: tracker exports made by numpy from the ISO
definitions (bags/independent/iso_generator), never by metrocell.

    python3 bags/independent/generate_suite.py --out DIR --seeds 1 2 3 [--sample] [--no-role]

Writes, per case and seed, DIR/case_NNN/seed_S/{export.csv, mapping.yaml, model.yaml} (neutral
case names, in a fixed shuffled order), for the sign-reversed reversal case also
model_backlash_free.yaml (backlash[y] declared free, for `metrocell calibrate`), and the answer
key DIR/answers.json, which only the scorer reads. Deterministic per seed. `--sample` writes the
small representative subset of iso_generator/cases.py SAMPLE. `--no-role` leaves out the Role
column and the reference-nest readings (for a `bag import` that does not know the `role` key).
"""

import argparse
import datetime as dt
import json
import os
import sys
import zlib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from catalog_translation import translate  # noqa: E402
from iso_generator import arm_recording, delta_recording, models  # noqa: E402
from iso_generator import xfyz_recording as xr  # noqa: E402
from iso_generator.cases import CASES, SAMPLE  # noqa: E402
from iso_generator.export import write_csv, write_mapping  # noqa: E402

MAPPING_COMMENT = """Mapping of the independent tracker export (bags/independent/generate_suite.py) onto
metrocell's point CSV layout: mm -> m, U95 (k = 2) in mm, hPa -> Pa, %RH -> 0..1, feeds in
mm/s -> m/s, the axis positions as joint values (m), the UTC date-time stamps as they are."""


def case_names():
    """Neutral names in an order that does not follow the table (fixed, seed-independent)."""
    order = np.random.default_rng(20250617).permutation(len(CASES))
    return {CASES[i].key: f"case_{n + 1:03d}" for n, i in enumerate(order)}


def epoch_start(case_index, seed):
    start = dt.datetime(2025, 3, 3, 6, 0, tzinfo=dt.timezone.utc) + dt.timedelta(days=case_index + 97 * seed, minutes=7 * case_index)
    return start.timestamp()


def family_of(spec, concealed):
    needs = set().union(*[c.needs for c in concealed]) if concealed else set()
    if spec.family:
        return spec.family, needs
    if "fly" in needs:
        return "fly", needs
    if "shift" in needs:
        return "shift", needs
    return "geometry", needs


def _needs_probe(spec):
    """The needs of a case's recipes (drawn on a scratch setting with a scratch generator)."""
    scratch = xr.Setting(np.random.default_rng(0), "geometry")
    return [recipe(np.random.default_rng(0), scratch, f) for recipe, f in spec.parts]


def build_xfyz(spec, seed, rng, epoch, no_role=False):
    family, needs = family_of(spec, _needs_probe(spec))
    setting = xr.Setting(rng, family, steady="steady" in needs)
    concealed = [recipe(rng, setting, f) for recipe, f in spec.parts]
    readings, sim, size, tracker = xr.simulate(setting, concealed, rng, noise=spec.noise)
    cols, station = xr.columns(setting, readings, sim, rng, epoch)
    t = readings["t"]
    station_mean = {"temperature_c": float(np.mean(station["temperature_c"])),
                    "pressure_pa": float(np.mean(station["pressure_hpa"]) * 100.0),
                    "humidity_rh": float(np.mean(station["humidity_pct"]) / 100.0)}
    # the recording's time span as exported (without the role column the nests are left out)
    exported = ~sim["is_nest"] if no_role else np.ones(len(t), bool)
    context = {"travel": setting.travel, "station_mean": station_mean,
               "time_span_s": (float(t[exported].min()), float(t[exported].max()))}
    effects = []
    for c in concealed:
        if c.refraction is not None:
            context["refraction_scale_mean"] = float(np.mean(c.refraction.scale(t)))
            c.truth = {**c.truth, **c.refraction.truth(t)}
        effects.append({"effect": c.effect_id, "truth": c.truth, "expected": translate(c.effect_id, c.truth, context)})
    model = models.xfyz_model("shop_machine", setting.travel, setting.tool_offset)
    meta = {"family": family, "machine": "XFYZ", "travel_m": setting.travel, "tool_offset_m": setting.tool_offset.tolist(),
            "duration_s": float(t.max()), "rows": int(len(t)), "reference_rows": int(sim["is_nest"].sum()),
            "moving_rows": int(readings["moving"].sum()), "tracker": tracker.truth(),
            "range_m": [float(sim["range"].min()), float(sim["range"].max())],
            "station_mean": station_mean, "power_on_s": setting.power_on_s}
    return cols, model, effects, size, meta, setting


def build_arm_or_delta(spec, which, f, rng, epoch):
    if which == "arm":
        out = arm_recording.build(rng, f, epoch)
        model = models.arm_model("ur5_cell", out["tool_nominal"])
        effect_id = "arm_tool_offset"
    else:
        out = delta_recording.build(rng, f, epoch)
        model = models.delta_model("delta_cell", delta_recording.ROD, delta_recording.RADIUS, delta_recording.TRAVEL, out["tool_offset"])
        effect_id = "delta_rod_length"
    effects = [{"effect": effect_id, "truth": out["truth"], "expected": translate(effect_id, out["truth"], {"travel": None})}]
    meta = {"family": which, "machine": "UR5" if which == "arm" else "linear delta", "rows": out["rows"],
            "duration_s": out["duration_s"], "tracker": out["tracker"].truth()}
    return out["columns"], model, effects, out["size"], meta


def calibrate_model(model_text):
    """The user's model with backlash[y] declared and its reversal free (for `metrocell calibrate`)."""
    return model_text.replace("terms: []", """terms:
  - id: backlash
    options: {axis: y}
    params: {reversal: 0 um}

estimation:
  backlash[y]: {free: [reversal]}""")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--sample", action="store_true", help="only the representative subset (iso_generator/cases.py SAMPLE)")
    ap.add_argument("--cases", nargs="*", help="only these case keys (iso_generator/cases.py)")
    ap.add_argument("--no-role", action="store_true", help="leave out the Role column")
    a = ap.parse_args()
    names = case_names()
    specs = [c for c in CASES if (not a.sample or c.key in SAMPLE) and (not a.cases or c.key in a.cases)]
    os.makedirs(a.out, exist_ok=True)
    answers = {"generator": "bags/independent/generate_suite.py", "seeds": a.seeds, "cases": {}}
    for spec in specs:
        case = names[spec.key]
        index = [c.key for c in CASES].index(spec.key)
        entry = {"key": spec.key, "kind": spec.kind, "category": spec.category, "note": spec.note, "noise": spec.noise, "seeds": {}}
        for seed in a.seeds:
            rng = np.random.default_rng([zlib.crc32(spec.key.encode()), seed])
            epoch = epoch_start(index, seed)
            if spec.parts and spec.parts[0][0] in ("arm", "delta"):
                cols, model, effects, size, meta = build_arm_or_delta(spec, spec.parts[0][0], spec.parts[0][1], rng, epoch)
            else:
                cols, model, effects, size, meta, _ = build_xfyz(spec, seed, rng, epoch, a.no_role)
            if a.no_role:
                # without the role column a reference nest's reading would pass for a tool point:
                # leave the nests out too
                role = next(c for c in cols if c.key == "role").values
                keep = [i for i, r in enumerate(role) if r != "reference"]
                for c in cols:
                    c.values = [c.values[i] for i in keep]
                cols = [c for c in cols if c.key != "role"]
            d = os.path.join(a.out, case, f"seed_{seed}")
            os.makedirs(d, exist_ok=True)
            write_csv(os.path.join(d, "export.csv"), cols)
            write_mapping(os.path.join(d, "mapping.yaml"), cols, "tracker_export", comment=MAPPING_COMMENT)
            with open(os.path.join(d, "model.yaml"), "w") as f:
                f.write(model)
            if spec.key == "reversal_y_overcompensated":
                with open(os.path.join(d, "model_backlash_free.yaml"), "w") as f:
                    f.write(calibrate_model(model))
            entry["seeds"][str(seed)] = {"effects": effects, **size, **meta}
        answers["cases"][case] = entry
        print(f"{case}  {spec.key:36s} " + "  ".join(
            f"s{s}: {entry['seeds'][str(s)]['rows']} rows, peak {entry['seeds'][str(s)]['effect_peak_in_noise']:.1f}x noise" for s in a.seeds),
            flush=True)
    with open(os.path.join(a.out, "answers.json"), "w") as f:
        json.dump(answers, f, indent=1, sort_keys=True, default=float)
    print(f"wrote {len(specs)} cases x {len(a.seeds)} seeds to {a.out} (answer key: {os.path.join(a.out, 'answers.json')})")


if __name__ == "__main__":
    main()
