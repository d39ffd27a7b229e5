#!/usr/bin/env python3
"""Regenerate the concealed-effect suite's recordings from the cell files and seeds.

    python3 bags/generate.py --metrocell target/release/metrocell --out /tmp/suite --seeds 1 2 3
    python3 bags/generate.py --metrocell target/release/metrocell --out /tmp/suite --seeds 1 --cases case_03 case_07

For every case and seed: `metrocell sim --cell bags/cases/case_NN/truth.yaml --seed S` writes the
raw recording (no /clock); then `metrocell bag filter` / `bag merge` keep only what a point
measurement needs, writing OUT/case_NN/seed_S (a rosbag2 MCAP directory):
  * the tracker readings and the commanded joint states inside each program cycle (the windows
    of bags/recordings.json, written by bags/cases.py; between cycles the machine idles at home),
  * every other topic over the whole recording (temperatures, and whatever else the twin writes
    at low rate: the lagged thermal terms need the temperature history before each cycle),
  * never `/machine/joint_states`: the twin's *actual* positions are commanded + the true error,
    which no real controller reports and which would hand the answer to any method.
Nothing in the result names the concealed term: the bag's directory and file names are neutral,
`metrocell sim` writes no cell name into messages or metadata (frame ids are `tracker`,
`workpiece` and the thermocouples' locations), and bag filter/merge copy messages unchanged.

Deterministic: the same cell files and seed give the same messages (topics, log times, bytes);
the MCAP chunking of `bag filter`/`merge` may differ between runs, the messages do not.
Standard library only (`--verify` reads the bags with the `mcap` packages).
"""

import argparse
import datetime
import json
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
HIGH_RATE = ["/tracker/measurements", "/machine/commanded_joint_states"]
# topics never kept: the twin's actual joint positions (the answer), rendered camera frames
# (large; a camera case would keep the fiducial node's detections instead), and the clock
DROPPED = ["/machine/joint_states", "/camera/image_raw", "/clock"]


def run(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        sys.exit(f"generate.py: `{' '.join(cmd)}` failed ({p.returncode}):\n{p.stderr}")
    return p.stdout


def anchored(topics):
    return "^(" + "|".join(t.replace("/", "\\/") for t in topics) + ")$"


def run_dirs(out, case, seed, plan):
    """Bag directories of one case and seed: OUT/case/seed_S, and OUT/case/seed_S_run2, ... when
    the case is recorded in several runs (e.g. unloaded and loaded)."""
    base = os.path.join(out, case, f"seed_{seed}")
    return [base] + [f"{base}_run{k}" for k in range(2, len(plan.get("runs", ["truth.yaml"])) + 1)]


# the first run of every case starts at metrocell sim's default start time; run k an hour per
# run later, so the runs of one case follow each other in time
START = datetime.datetime(2026, 1, 5, 6, 0, 0, tzinfo=datetime.timezone.utc)
RUN_SPACING = datetime.timedelta(hours=1)


def generate(metrocell, case, seed, plan, out_dir, truth_file="truth.yaml", run_index=0):
    """Write one recording to out_dir (which must not exist)."""
    truth = os.path.join(HERE, "cases", case, truth_file)
    start = (START + run_index * max(RUN_SPACING, datetime.timedelta(seconds=plan["duration_s"] + 600))).strftime("%Y-%m-%dT%H:%M:%SZ")
    with tempfile.TemporaryDirectory(prefix=f"suite_{case}_") as tmp:
        raw = os.path.join(tmp, "raw")
        run([metrocell, "sim", "--cell", truth, "--duration", str(plan["duration_s"]), "--seed", str(seed),
             "--start-time", start, "--clock-rate", "0", "--quiet", "-o", raw])
        parts = [os.path.join(tmp, "whole")]
        run([metrocell, "bag", "filter", raw, parts[0], "--exclude", anchored(HIGH_RATE + DROPPED)])
        for k, (a, b) in enumerate(plan["windows_s"]):
            part = os.path.join(tmp, f"cycle_{k:03d}")
            run([metrocell, "bag", "filter", raw, part, "--topics", *HIGH_RATE, "--start", repr(a), "--end", repr(b)])
            parts.append(part)
        os.makedirs(os.path.dirname(out_dir), exist_ok=True)
        run([metrocell, "bag", "merge", out_dir, *parts])


# catalog ids (crates/physics/src/term_id.rs) and words that would give the answer away
TELLTALES = ["angular", "backlash", "camera_scale", "compliance", "delta_endstop", "delta_radius", "delta_rod_length",
             "delta_tower_angle", "frame_misalignment", "joint_offset", "lens_distortion", "link_length", "pitch_cyclic",
             "positioning", "probe_pretravel", "refraction", "squareness", "straightness", "thermal_growth", "thermal_scale",
             "time_offset", "tool_offset", "tracker_pose", "tracker_warmup", "turbulence", "workpiece_expansion", "rotary_axis_location",
             "concealed", "truth", "disturb", "answer"]


def strings_of(value):
    """Every string inside a decoded ROS message (fields, arrays, nested messages)."""
    if isinstance(value, str):
        yield value
    elif isinstance(value, (list, tuple)):
        for v in value:
            yield from strings_of(v)
    elif hasattr(value, "__slots__") or hasattr(value, "__dict__"):
        names = getattr(value, "__slots__", None) or list(vars(value))
        for n in names:
            yield from strings_of(getattr(value, n, None))


def verify(out_dir):
    """Problems with a recording: a topic that gives the answer (actual joint states), or a
    catalog id / telltale word in a file name, metadata.yaml, the MCAP header, metadata or
    channel records, or any string field of any message. Message definitions (schemas) are the
    shipped .msg texts, the same in every recording, and are not searched. Needs the Python
    packages `mcap` and `mcap-ros2-support` (tests/requirements.txt)."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    problems = []

    def scan(where, text):
        low = text.lower()
        problems.extend(f"{where}: `{w}` in {text[:120]!r}" for w in TELLTALES if w in low)

    for name in os.listdir(out_dir):
        scan(f"file name {name}", name)
    scan("metadata.yaml", open(os.path.join(out_dir, "metadata.yaml")).read())
    for name in sorted(n for n in os.listdir(out_dir) if n.endswith(".mcap")):
        with open(os.path.join(out_dir, name), "rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            h = reader.get_header()
            scan(f"{name} header", f"{h.profile} {h.library}")
            for m in reader.iter_metadata():
                scan(f"{name} metadata {m.name}", m.name + " " + json.dumps(m.metadata))
            for ch in reader.get_summary().channels.values():
                if ch.topic in DROPPED:
                    problems.append(f"{name}: topic {ch.topic} must not be in a suite recording")
                scan(f"{name} channel {ch.topic}", ch.topic + " " + json.dumps(ch.metadata))
            seen = set()
            for _, ch, _, msg in reader.iter_decoded_messages():
                for s in strings_of(msg):
                    if s not in seen:
                        seen.add(s)
                        scan(f"{name} {ch.topic} message", s)
    return problems


def digest(out_dir):
    """sha256 over every message of a recording in log-time order (topic, log time, CDR bytes):
    equal for equal messages, whatever the MCAP chunking."""
    import hashlib
    from mcap.reader import make_reader

    h = hashlib.sha256()
    for name in sorted(n for n in os.listdir(out_dir) if n.endswith(".mcap")):
        with open(os.path.join(out_dir, name), "rb") as f:
            for _, ch, msg in make_reader(f).iter_messages(log_time_order=True):
                h.update(ch.topic.encode() + b"\0" + msg.log_time.to_bytes(8, "little") + len(msg.data).to_bytes(8, "little") + msg.data)
    return h.hexdigest()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--metrocell", help="the metrocell binary (cargo build --release -p metrocell-cli)")
    ap.add_argument("--out", help="directory for OUT/case_NN/seed_S bags")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--cases", nargs="*", help="case names (default: every case)")
    ap.add_argument("--force", action="store_true", help="replace recordings that already exist")
    ap.add_argument("--verify", action="store_true", help="check each recording names nothing of the answer (needs mcap, mcap-ros2-support)")
    ap.add_argument("--verify-only", metavar="BAG", help="only check an existing bag (any bag) and exit 1 if it names the answer")
    ap.add_argument("--digest", metavar="BAG", help="only print the message digest of an existing bag")
    a = ap.parse_args(argv)
    if a.verify_only:
        problems = verify(a.verify_only)
        print("\n".join(problems) if problems else f"{a.verify_only}: names nothing of the answer")
        return 1 if problems else 0
    if a.digest:
        print(digest(a.digest))
        return 0
    plans = json.load(open(os.path.join(HERE, "recordings.json")))
    if not (a.metrocell and a.out):
        ap.error("--metrocell and --out are required to generate recordings")
    cases = a.cases or sorted(plans)
    unknown = [c for c in cases if c not in plans]
    if unknown:
        sys.exit(f"generate.py: unknown case(s) {unknown}; the suite has {sorted(plans)}")
    for case in cases:
        plan = plans[case]
        for seed in a.seeds:
            for k, (out_dir, truth_file) in enumerate(zip(run_dirs(a.out, case, seed, plan), plan.get("runs", ["truth.yaml"]))):
                if os.path.exists(out_dir):
                    if not a.force:
                        print(f"{out_dir}: exists, kept (--force replaces it)")
                        continue
                    shutil.rmtree(out_dir)
                # run k of a case gets its own noise: seed + 1000 k
                generate(a.metrocell, case, seed + 1000 * k, plan, out_dir, truth_file, k)
                size = sum(os.path.getsize(os.path.join(out_dir, f)) for f in os.listdir(out_dir))
                print(f"{out_dir}: {size / 1024:.0f} KiB")
                if a.verify:
                    problems = verify(out_dir)
                    if problems:
                        sys.exit(f"generate.py: {out_dir} gives the answer away:\n  " + "\n  ".join(problems))
    return 0


if __name__ == "__main__":
    sys.exit(main())
