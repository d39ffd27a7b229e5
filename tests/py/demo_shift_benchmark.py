"""A shift under `metrocell demo`, measured: every node's memory, the recording, the page.

Runs the demo (its arguments after `--`, e.g. `--quick` for 1 h of cell time), samples the
resident memory (VmRSS) of every process the demo started (its descendants in /proc, so another
user's nodes on the same machine are not counted) every PERIOD seconds, and opens the dashboard
it serves in headless Chromium for the run (tests/py/dashboard_browser.py: time to first paint,
the latency from each push to the page showing it, console errors). At the end: per process its
RSS at the first sample, after 10 s and at the last sample before the nodes stopped, and the
largest; the demo's recording check (messages, missing), the bag's size, the load average.
Prints a JSON object, then the same figures as Markdown.

Run inside the private network namespace (the demo opens DDS participants), with the Python of
the test venv (the browser driver needs `websockets`):

    tests/isolated .venv/bin/python tests/py/demo_shift_benchmark.py target/release/metrocell -- --quick
"""
import argparse
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def descendants(root):
    """pid → executable name of every live process below `root` (itself included)."""
    parent, name = {}, {}
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/stat") as f:
                stat = f.read()
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                argv0 = f.read().split(b"\0")[0].decode(errors="replace")
        except OSError:
            continue
        # the command name in parentheses may hold spaces: the ppid follows the last ')'
        parent[int(pid)] = int(stat.rsplit(")", 1)[1].split()[1])
        name[int(pid)] = os.path.basename(argv0)
    out, frontier = {}, [root]
    while frontier:
        p = frontier.pop()
        if p in name:
            out[p] = name[p]
            frontier.extend(c for c, pp in parent.items() if pp == p)
    return out


def rss_kb(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return None


def load_average():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def port_open(port):
    with socket.socket() as s:
        s.settimeout(0.2)
        return s.connect_ex(("127.0.0.1", port)) == 0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("metrocell", help="the metrocell binary")
    ap.add_argument("--period", type=float, default=2.0, help="seconds between memory samples")
    ap.add_argument("--chromium", default="/usr/bin/chromium")
    ap.add_argument("--port", type=int, default=8765, help="the dashboard's port (the demo's --dashboard-port)")
    ap.add_argument("demo_args", nargs="*", help="arguments of `metrocell demo` (after --)")
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="demo_shift_bench_")
    bag = os.path.join(work, "bag")
    demo = subprocess.Popen([a.metrocell, "demo", "-o", bag, "--dashboard-port", str(a.port), *a.demo_args],
                            stdout=subprocess.PIPE, stderr=open(os.path.join(work, "demo.err"), "w"), text=True)
    stdout = []
    threading.Thread(target=lambda: stdout.extend(demo.stdout), daemon=True).start()
    started = time.monotonic()
    samples = {}  # name → [(t, kB)]
    loads = [load_average()]
    browser = None
    while demo.poll() is None:
        t = time.monotonic() - started
        for pid, name in descendants(demo.pid).items():
            kb = rss_kb(pid)
            if kb is not None and name.startswith("metrocell"):
                samples.setdefault(name, []).append((round(t, 1), kb))
        loads.append(load_average())
        if browser is None and port_open(a.port):
            # watch the page until shortly before the run ends (the demo's own estimate)
            wall = next((float(m.group(1)) * (60 if m.group(2) == "min" else 1)
                         for m in [re.search(r"about (\d+) (min|s) of wall time", "".join(stdout))] if m), 60.0)
            browser = subprocess.Popen([sys.executable, os.path.join(HERE, "dashboard_browser.py"), a.chromium, f"http://127.0.0.1:{a.port}/",
                                        os.path.join(work, "dashboard.png"), "--watch", str(max(5.0, wall - 15.0))],
                                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(a.period)
    page = None
    if browser is not None:
        out, err = browser.communicate(timeout=120)
        page = json.loads(out) if browser.returncode == 0 else {"error": err[-2000:]}
    text = "".join(stdout)
    check = next((l for l in text.splitlines() if l.startswith("recording check:")), None)
    camera = next((l for l in text.splitlines() if l.startswith("camera:")), None)
    bag_bytes = sum(os.path.getsize(os.path.join(bag, f)) for f in os.listdir(bag)) if os.path.isdir(bag) else None
    memory = {}
    for name, s in sorted(samples.items()):
        after_10 = next((kb for t, kb in s if t >= 10.0), None)
        memory[name] = {"start_kb": s[0][1], "after_10s_kb": after_10, "end_kb": s[-1][1], "max_kb": max(kb for _, kb in s),
                        "samples": len(s), "last_sample_s": s[-1][0], "series_mb": [round(kb / 1024, 1) for _, kb in s]}
    result = {"demo_args": a.demo_args, "exit": demo.returncode, "wall_s": round(time.monotonic() - started, 1), "recording_check": check,
              "camera": camera, "bag_bytes": bag_bytes, "load_average": {"start": loads[0], "max": max(loads), "end": loads[-1]}, "memory": memory}
    if page and "second" in page:
        lat = sorted(page["second"]["latencies_ms"])
        result["page"] = {"first_contentful_paint_ms": page["second"]["fcp_ms"], "first_update_ms": page["second"]["first_update_ms"],
                          "updates": len(lat), "latency_p50_ms": lat[len(lat) // 2] if lat else None,
                          "latency_p95_ms": lat[(len(lat) * 95) // 100] if lat else None, "console_errors": page["console_errors"]}
    else:
        result["page"] = page
    json.dump(result, sys.stdout, indent=1)
    print("\n\n| process | RSS at start | after 10 s | end | max |\n|---|---|---|---|---|")
    for name, m in memory.items():
        mb = lambda kb: "—" if kb is None else f"{kb / 1024:.1f} MB"
        print(f"| {name} | {mb(m['start_kb'])} | {mb(m['after_10s_kb'])} | {mb(m['end_kb'])} (at {m['last_sample_s']:.0f} s) | {mb(m['max_kb'])} |")
    print(f"\n{check}\n{camera}\nbag {bag_bytes / 2**20:.1f} MiB" if bag_bytes else f"\n{check}")
    shutil.rmtree(work, ignore_errors=True)
    sys.exit(demo.returncode)


if __name__ == "__main__":
    main()
