"""The soak (issue 31, item 3): a long shift under `metrocell demo` with the diagnose node's window
full for most of it; every node's memory after its warm-up, the recording, the logs.

Runs `metrocell demo` for `--duration` s of cell time at `--speed` with the live diagnose node's
window (`--diagnose-window`) shorter than the shift, samples every process the demo started
(demo_shift_benchmark.descendants) every `--period` s for VmRSS, VmHWM and its thread count, and
reads the demo's stdout (its progress lines give cell time against wall time) and every node's
log (the launcher prefixes each node's stderr with `[name]`) as they arrive.

Warm-up, per node:
- the diagnose node: until its first diagnosis of a full window has finished (its log line
  `run N over X h of cell time`, X the window) once the temperatures' full-rate span (the window
  and `--lag-margin` before it) is full too. Before, the window grows by ~25 MB per hour of cell
  time, each diagnosis's working copies grow with it, and the lag caches by ~1.4 MB per hour;
  after, all should stay put.
- every other node: the first `--warmup-h` hours of cell time (3 h). Their caches and DDS
  histories are bounded by sample counts (BENCHMARKS.md, *A shift under metrocell demo*), so they
  fill within a fixed stretch of cell time: the last to fill are the twin's writer histories,
  8192 samples each in RustDDS (crates/node qos.rs), which its temperatures (1 Hz) reach at 2.3 h
  and its /clock (~0.83 Hz) at 2.7 h; slower topics (camera_info, one per 15 s) never do, but
  hold a few kB.

After its warm-up (up to the end of the shift's cell time, not the demo's summary after it), per
node: the RSS at the end of the warm-up (the reference), the largest deviation from it in % of
it, and the least-squares slope in MB per hour of cell time; flat means within `--tolerance`
(10 %). The diagnose node is judged on the samples taken between diagnoses (its thread count at
its least: the worker thread of a diagnosis is gone), since during a diagnosis it holds working
copies of the window and gives them back after (nodes/diagnose session.rs, `run_job`); its
diagnoses' peak (VmHWM) must not grow by more than the tolerance either. A sampled peak is
reported for each of its diagnoses.

Also: the demo's recording check (the twin's messages against the bag: 0 missing), the
recorder's own account, and every log line at ERROR or FATAL (or a panic) — there must be none.

Writes the figures as JSON (`--json`, else stdout) and as Markdown; exits 0 only if every node is
flat, nothing is missing and no log has an error. Run inside the private network namespace (the
demo opens DDS participants):

    tests/isolated .venv/bin/python tests/py/soak.py target/release/metrocell \\
        --duration 28800 --speed 120 --diagnose-window 7200
"""
import argparse
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from demo_shift_benchmark import descendants, load_average  # noqa: E402


def proc_status(pid):
    """VmRSS [kB], VmHWM [kB] and the thread count of a live process, or None."""
    fields = {}
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                key, _, value = line.partition(":")
                if key in ("VmRSS", "VmHWM", "Threads"):
                    fields[key] = int(value.split()[0])
    except OSError:
        return None
    return fields if len(fields) == 3 else None


def stop_with_parent():
    """In the demo's child before exec: SIGINT when this script dies (also by SIGKILL, e.g. a test's
    timeout), so the demo stops its nodes rather than leave them running."""
    import ctypes
    ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGINT)  # PR_SET_PDEATHSIG


def read_lines(stream, sink, started, echo=None):
    """Appends (wall s since start, line) for each line of `stream` as it arrives."""
    for line in stream:
        sink.append((time.monotonic() - started, line.rstrip("\n")))
        if echo:
            print(line, end="", file=echo, flush=True)


CELL_TIME = re.compile(r"^\s+cell time (\d+):(\d\d):(\d\d)\s")


def cell_clock(stdout, speed):
    """Wall s → cell s, from the demo's progress lines (interpolated; past the last, at `speed`)."""
    points = []
    for wall, line in stdout:
        m = CELL_TIME.match(line)
        if m:
            cell = int(m.group(1)) * 3600 + int(m.group(2)) * 60 + int(m.group(3))
            if not points or cell > points[-1][1]:
                points.append((wall, cell))
    if not points:
        return None

    def at(wall):
        if wall <= points[0][0]:
            return points[0][1] - (points[0][0] - wall) * speed
        for (w0, c0), (w1, c1) in zip(points, points[1:]):
            if wall <= w1:
                return c0 + (c1 - c0) * (wall - w0) / (w1 - w0)
        return points[-1][1] + (wall - points[-1][0]) * speed

    return at


def wall_at_cell(clock, cell, wall_end):
    """The first wall time at which `clock` reaches `cell` (bisection; the map is monotone)."""
    lo, hi = 0.0, wall_end
    if clock(hi) < cell:
        return None
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if clock(mid) < cell else (lo, mid)
    return hi


def slope_per_hour(points):
    """Least-squares slope of (cell s, kB) as MB per hour of cell time."""
    n = len(points)
    if n < 2:
        return None
    mx = sum(c for c, _ in points) / n
    my = sum(kb for _, kb in points) / n
    sxx = sum((c - mx) ** 2 for c, _ in points)
    if sxx == 0:
        return None
    sxy = sum((c - mx) * (kb - my) for c, kb in points)
    return sxy / sxx * 3600 / 1024


DIAGNOSIS = re.compile(r"\[diagnose\]: run (\d+) over ([\d.]+) h of cell time")
ERROR = re.compile(r"\[(ERROR|FATAL)\]|panicked at")


def judge(name, series, warm_wall, end_wall, clock, tolerance, resting_only=False):
    """The figures of one node's samples [(wall, rss, hwm, threads)] after its warm-up."""
    during = [s for s in series if s[0] <= end_wall]
    after = [s for s in during if s[0] >= warm_wall]
    if resting_only and after:
        least = min(s[3] for s in after)
        after = [s for s in after if s[3] == least]
    if len(after) < 3:
        return {"node": name, "error": f"{len(after)} samples after the warm-up", "flat": False}
    ref = after[0][1]
    worst = max(after, key=lambda s: abs(s[1] - ref))
    out = {
        "node": name,
        "start_mb": round(series[0][1] / 1024, 1),
        "warmup_end_cell_h": round(clock(warm_wall) / 3600, 2),
        "warmup_end_mb": round(ref / 1024, 1),
        "end_mb": round(after[-1][1] / 1024, 1),
        "max_mb": round(max(s[1] for s in during) / 1024, 1),
        "max_after_warmup_mb": round(max(s[1] for s in after) / 1024, 1),
        "min_after_warmup_mb": round(min(s[1] for s in after) / 1024, 1),
        "deviation_pct": round(100 * abs(worst[1] - ref) / ref, 1),
        "deviation_at_cell_h": round(clock(worst[0]) / 3600, 2),
        "slope_mb_per_h": round(slope_per_hour([(clock(s[0]), s[1]) for s in after]), 2),
        "samples_after_warmup": len(after),
        # the course, at most ~60 points: (cell h, MB)
        "course": [(round(clock(s[0]) / 3600, 2), round(s[1] / 1024, 1)) for s in during[::max(1, len(during) // 60)]],
    }
    out["flat"] = out["deviation_pct"] <= 100 * tolerance
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("metrocell", help="the metrocell binary")
    ap.add_argument("--duration", type=float, default=28800.0, help="s of cell time (default: an 8-h shift)")
    ap.add_argument("--speed", type=float, default=120.0, help="cell s per wall s")
    ap.add_argument("--diagnose-window", type=float, default=7200.0, help="s of cell time the diagnose node looks back over")
    ap.add_argument("--warmup-h", type=float, default=3.0, help="hours of cell time: the warm-up of every node but diagnose")
    ap.add_argument("--lag-margin", type=float, default=3600.0, help="s of temperature history the diagnose node keeps at full rate before its window (crates/records LAG_FULL_RATE_MARGIN_S)")
    ap.add_argument("--tolerance", type=float, default=0.10, help="flat: within this fraction of the warm-up-end RSS")
    ap.add_argument("--period", type=float, default=2.0, help="s between memory samples")
    ap.add_argument("--json", help="write the figures here (else to stdout)")
    ap.add_argument("--log", help="copy the demo's stdout and stderr here")
    ap.add_argument("--echo", action="store_true", help="echo the demo's stdout as it runs")
    a = ap.parse_args()

    work = tempfile.mkdtemp(prefix="soak_")
    bag = os.path.join(work, "bag")
    started = time.monotonic()
    demo = subprocess.Popen(
        [a.metrocell, "demo", "-o", bag, "--dashboard-port", "0", "--duration", str(a.duration), "--speed", str(a.speed),
         "--diagnose-window", str(a.diagnose_window)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, errors="replace", preexec_fn=stop_with_parent)
    stdout, stderr = [], []
    readers = [threading.Thread(target=read_lines, args=(demo.stdout, stdout, started, sys.stderr if a.echo else None), daemon=True),
               threading.Thread(target=read_lines, args=(demo.stderr, stderr, started), daemon=True)]
    for r in readers:
        r.start()
    series = {}  # name → [(wall s, VmRSS kB, VmHWM kB, threads)]
    loads = [load_average()]
    while demo.poll() is None:
        t = time.monotonic() - started
        for pid, name in descendants(demo.pid).items():
            st = proc_status(pid)
            if st is not None and name.startswith("metrocell"):
                series.setdefault(name, []).append((t, st["VmRSS"], st["VmHWM"], st["Threads"]))
        loads.append(load_average())
        time.sleep(a.period)
    for r in readers:
        r.join(timeout=10)
    wall = time.monotonic() - started
    if a.log:
        with open(a.log, "w") as f:
            f.writelines(f"{w:8.1f} out {line}\n" for w, line in stdout)
            f.writelines(f"{w:8.1f} err {line}\n" for w, line in stderr)

    result = {"command": demo.args, "exit": demo.returncode, "wall_s": round(wall, 1), "duration_s": a.duration, "speed": a.speed,
              "diagnose_window_s": a.diagnose_window, "warmup_h": a.warmup_h, "tolerance": a.tolerance,
              "load_average": {"start": loads[0], "max": max(loads), "end": loads[-1]}}
    problems = []
    clock = cell_clock(stdout, a.speed)
    if clock is None:
        problems.append("no progress line from the demo: the cell never ran")
        result["problems"] = problems
        print("\n".join(line for _, line in stdout + stderr)[-20000:], file=sys.stderr)
    else:
        end_wall = wall_at_cell(clock, a.duration, wall) or wall
        result["cell_run_wall_s"] = round(end_wall - (wall_at_cell(clock, 0.0, wall) or 0.0), 1)
        # the diagnose node's runs: when each ended, over how much cell time
        runs = [{"run": int(m.group(1)), "window_h": float(m.group(2)), "wall_s": round(w, 1), "cell_h": round(clock(w) / 3600, 2)}
                for w, line in stderr for m in [DIAGNOSIS.search(line)] if m]
        # its memory is full once the window is and the temperatures' full-rate span behind it
        # (window + LAG_FULL_RATE_MARGIN_S, crates/records; older history is coarsened in
        # batches of 10 min): the first diagnosis done after both
        span_h = (a.diagnose_window + a.lag_margin + 600.0) / 3600
        full = next((r for r in runs if r["window_h"] >= a.diagnose_window / 3600 - 0.02 and r["cell_h"] >= span_h), None)
        result["diagnoses"] = runs
        # the sampled peak of each diagnosis: the diagnose node's largest RSS since the previous run ended
        diag = series.get("metrocell-diagnose", [])
        prev = 0.0
        for k, r in enumerate(runs):
            inside = [s[1] for s in diag if prev < s[0] <= r["wall_s"] + a.period]
            r["sampled_peak_mb"] = round(max(inside) / 1024, 1) if inside else None
            # what it holds once the run has given its memory back: the least until the next run ends
            until = runs[k + 1]["wall_s"] if k + 1 < len(runs) else wall
            rest = [s[1] for s in diag if r["wall_s"] + a.period < s[0] <= until]
            r["rest_after_mb"] = round(min(rest) / 1024, 1) if rest else None
            prev = r["wall_s"]
        others_warm = wall_at_cell(clock, a.warmup_h * 3600, wall) or wall
        nodes = []
        for name, s in sorted(series.items()):
            if name == "metrocell-diagnose":
                if full is None:
                    nodes.append({"node": name, "error": "its window was never full (no diagnosis over the whole window)", "flat": False})
                    continue
                j = judge(name, s, full["wall_s"], end_wall, clock, a.tolerance, resting_only=True)
                hwm_at = [x[2] for x in s if x[0] <= full["wall_s"] + a.period]
                if "error" not in j and hwm_at:
                    j["warmup"] = f"until run {full['run']}, its first over the full window"
                    j["hwm_warmup_end_mb"] = round(hwm_at[-1] / 1024, 1)
                    j["hwm_end_mb"] = round([x[2] for x in s if x[0] <= end_wall][-1] / 1024, 1)
                    j["hwm_growth_pct"] = round(100 * (j["hwm_end_mb"] / j["hwm_warmup_end_mb"] - 1), 1)
                    j["flat"] = j["flat"] and j["hwm_growth_pct"] <= 100 * a.tolerance
                    j["full_window_diagnoses_after_warmup"] = sum(1 for r in runs if r["wall_s"] > full["wall_s"] and r["wall_s"] <= end_wall + 30)
            else:
                j = judge(name, s, others_warm, end_wall, clock, a.tolerance)
                if "error" not in j:
                    j["warmup"] = f"the first {a.warmup_h:g} h of cell time"
            nodes.append(j)
        result["memory"] = nodes
        for n in nodes:
            if not n["flat"]:
                problems.append(f"{n['node']} not flat: " + (n.get("error") or json.dumps({k: v for k, v in n.items() if k != "course"})))
        # the recording: the demo's check (the twin against the bag) and the recorder's account
        check = next((line for _, line in stdout if line.startswith("recording check:")), None)
        m = re.search(r"\((\d+) on (\d+) topics, (\d+) missing\)", check or "")
        result["recording_check"] = check
        result["twin_messages"] = int(m.group(1)) if m else None
        result["missing"] = int(m.group(3)) if m else None
        if result["missing"] != 0:
            problems.append(f"recording: {check}")
        account = next((line for _, line in stderr if "messages recorded on" in line), None)
        result["recorder_account"] = account
        result["recorder_gaps"] = [line for _, line in stderr if line.startswith("[recorder]   /")]
        # the logs: every node's lines at ERROR/FATAL and any panic; WARN lines counted per node
        errors = [line for _, line in stderr if ERROR.search(line)]
        warns = {}
        for _, line in stderr:
            if "[WARN]" in line:
                node = line.split("]", 1)[0].lstrip("[")
                warns[node] = warns.get(node, 0) + 1
        result["log_errors"] = errors
        result["log_warnings_per_node"] = warns
        result["log_lines"] = len(stderr)
        if errors:
            problems.append(f"{len(errors)} error lines in the logs")
        if demo.returncode != 0:
            problems.append(f"the demo exited with {demo.returncode}")
        result["problems"] = problems
    shutil.rmtree(work, ignore_errors=True)

    text = json.dumps(result, indent=1)
    if a.json:
        with open(a.json, "w") as f:
            f.write(text)
    else:
        print(text)
    print(f"\nsoak: {a.duration / 3600:g} h of cell time at {a.speed:g}×, diagnose window {a.diagnose_window / 3600:g} h; "
          f"{result['wall_s']:.0f} s of wall time, load {loads[0]:.1f} / max {max(loads):.1f} / end {loads[-1]:.1f}")
    print("\n| process | start | warm-up ends (cell h) | at warm-up end | end | max after warm-up | largest deviation | slope | flat |\n|---|---|---|---|---|---|---|---|---|")
    for n in result.get("memory", []):
        if "error" in n:
            print(f"| {n['node']} | — | — | — | — | — | {n['error']} | — | no |")
            continue
        extra = (f"; peak (VmHWM) {n['hwm_warmup_end_mb']} → {n['hwm_end_mb']} MB ({n['hwm_growth_pct']:+.1f} %)"
                 if "hwm_growth_pct" in n else "")
        print(f"| {n['node']} | {n['start_mb']} MB | {n['warmup_end_cell_h']} | {n['warmup_end_mb']} MB | {n['end_mb']} MB | "
              f"{n['max_after_warmup_mb']} MB | {n['deviation_pct']} % (at {n['deviation_at_cell_h']} h){extra} | {n['slope_mb_per_h']:+.2f} MB/h | "
              f"{'yes' if n['flat'] else '**no**'} |")
    for r in result.get("diagnoses", []):
        print(f"diagnosis {r['run']}: over {r['window_h']} h, done at cell time {r['cell_h']} h, sampled peak {r['sampled_peak_mb']} MB, "
              f"then {r['rest_after_mb']} MB")
    print(f"{result.get('recording_check')}\n{result.get('recorder_account')}")
    for line in result.get("recorder_gaps", []):
        print(line)
    print(f"log lines {result.get('log_lines')}, errors {len(result.get('log_errors', []))}, warnings per node {result.get('log_warnings_per_node')}")
    for line in result.get("log_errors", []):
        print(f"  {line}")
    for p in problems:
        print(f"PROBLEM: {p}")
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
