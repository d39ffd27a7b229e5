"""Drive Debian's headless Chromium over the DevTools protocol to check the dashboard page.

Opens URL in a fresh profile, records console errors and uncaught exceptions, waits for the
page's first WebSocket update, samples what the page shows twice (SAMPLE_GAP apart) to see live
values change, reads the first contentful paint and the page's update latencies, and saves a
full-page PNG screenshot. Prints one JSON object with the findings.

    python dashboard_browser.py /usr/bin/chromium http://127.0.0.1:8765/ shot.png [--watch 8]
"""
import argparse
import asyncio
import base64
import json
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time

import websockets

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--remote-debugging-address=127.0.0.1", "--remote-debugging-port=0"]

# What the page shows, read in the page: the values a supervisor watches.
READ = """(() => {
  const q = s => Array.from(document.querySelectorAll(s)).map(e => e.textContent.trim());
  const d = window.__dashboard;
  return {
    cell_time: document.getElementById('cell-time').textContent,
    connection: document.getElementById('connection').textContent,
    banner: document.getElementById('banner').textContent,
    temperatures: q('td[data-sensor]'),
    tracker_count: (document.getElementById('tracker-count') || {}).textContent || null,
    tracker_flags: q('[data-flag] .state'),
    magnitudes: q('[id^=vol-magnitude-]'),
    drifts: q('td[data-drift-axis]'),
    parameters: q('td[data-parameter]'),
    alerts: q('[data-alert]'),
    updates: d.updates, first_update_ms: d.firstUpdateMs, latencies_ms: d.latenciesMs.slice(), page_errors: d.errors,
    fcp_ms: (performance.getEntriesByType('paint').find(p => p.name === 'first-contentful-paint') || {}).startTime || null,
  };
})()"""


class Cdp:
    def __init__(self, ws):
        self.ws, self.next_id, self.events, self.pending = ws, 0, [], {}

    async def pump(self):
        async for raw in self.ws:
            m = json.loads(raw)
            if "id" in m and m["id"] in self.pending:
                self.pending.pop(m["id"]).set_result(m)
            else:
                self.events.append(m)

    async def call(self, method, session=None, **params):
        self.next_id += 1
        fut = asyncio.get_running_loop().create_future()
        self.pending[self.next_id] = fut
        msg = {"id": self.next_id, "method": method, "params": params}
        if session:
            msg["sessionId"] = session
        await self.ws.send(json.dumps(msg))
        r = await asyncio.wait_for(fut, 30)
        if "error" in r:
            raise RuntimeError(f"{method}: {r['error']}")
        return r["result"]


async def drive(endpoint, url, shot, watch):
    async with websockets.connect(endpoint, max_size=None) as ws:
        cdp = Cdp(ws)
        pump = asyncio.create_task(cdp.pump())
        target = (await cdp.call("Target.createTarget", url="about:blank"))["targetId"]
        s = (await cdp.call("Target.attachToTarget", targetId=target, flatten=True))["sessionId"]
        for domain in ("Runtime.enable", "Log.enable", "Page.enable"):
            await cdp.call(domain, s)
        await cdp.call("Emulation.setDeviceMetricsOverride", s, width=1440, height=1000, deviceScaleFactor=1, mobile=False)
        started = time.monotonic()
        await cdp.call("Page.navigate", s, url=url)

        async def read():
            r = await cdp.call("Runtime.evaluate", s, expression=READ, returnByValue=True)
            return r["result"].get("value")

        first = None
        while time.monotonic() - started < 30:
            first = await read()
            if first and first["updates"] > 0 and first["first_update_ms"] is not None:
                break
            await asyncio.sleep(0.1)
        first_seen_s = time.monotonic() - started
        await asyncio.sleep(watch)
        second = await read()
        metrics = await cdp.call("Page.getLayoutMetrics", s)
        height = int(metrics["cssContentSize"]["height"])
        await cdp.call("Emulation.setDeviceMetricsOverride", s, width=1440, height=max(1000, height), deviceScaleFactor=1, mobile=False)
        await asyncio.sleep(0.5)
        png = base64.b64decode((await cdp.call("Page.captureScreenshot", s, format="png"))["data"])
        with open(shot, "wb") as f:
            f.write(png)
        console_errors = []
        for e in cdp.events:
            p = e.get("params", {})
            if e.get("method") == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                console_errors.append(" ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", [])))
            elif e.get("method") == "Runtime.exceptionThrown":
                console_errors.append(p["exceptionDetails"].get("exception", {}).get("description") or p["exceptionDetails"].get("text"))
            elif e.get("method") == "Log.entryAdded" and p["entry"]["level"] == "error":
                console_errors.append(p["entry"]["source"] + ": " + p["entry"]["text"])
        pump.cancel()
        return {"first": first, "second": second, "first_update_wall_s": first_seen_s, "console_errors": console_errors,
                "screenshot": shot, "screenshot_bytes": len(png)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("chromium")
    ap.add_argument("url")
    ap.add_argument("screenshot")
    ap.add_argument("--watch", type=float, default=8.0, help="seconds between the two samples")
    a = ap.parse_args()
    profile = tempfile.mkdtemp(prefix="metrocell-chromium-")
    proc = subprocess.Popen([a.chromium, *FLAGS, f"--user-data-dir={profile}", "about:blank"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        endpoint = None
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and endpoint is None:
            line = proc.stderr.readline()
            if not line:
                break
            m = re.search(r"DevTools listening on (ws://\S+)", line)
            endpoint = m.group(1) if m else None
        # keep draining chromium's stderr so a full pipe never blocks it
        threading.Thread(target=lambda: [None for _ in proc.stderr], daemon=True).start()
        if endpoint is None:
            sys.exit(f"chromium did not print its DevTools endpoint (exit {proc.poll()})")
        result = asyncio.run(drive(endpoint, a.url, a.screenshot, a.watch))
        json.dump(result, sys.stdout)
        print()
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
        shutil.rmtree(profile, ignore_errors=True)


if __name__ == "__main__":
    main()
