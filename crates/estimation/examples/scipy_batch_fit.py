"""scipy's side of batch_fit_vs_scipy: least_squares(method="trf") on the metrocell problem.

The residuals and the analytic Jacobian are metrocell's own (the shared model through the
records/residuals path), evaluated by the Rust parent on request over the pipe, so both solvers
work on the identical problem from the identical start. Protocol (little-endian f64):
  parent -> here: one JSON line {"n", "m", "x0", "lower", "upper", "runs"}
  here -> parent: b"E" + n f64 (x); parent -> here: m f64 residuals, then m*n f64 Jacobian (row-major)
  here -> parent: b"D" + one JSON line with the solution and each run's timings
"""
import json
import sys
import time

import numpy as np
from scipy.optimize import least_squares

inp = sys.stdin.buffer
out = sys.stdout.buffer
head = json.loads(inp.readline())
n, m = head["n"], head["m"]
x0 = np.array(head["x0"])
# null: that side of the parameter's possible range is unbounded
lower = np.array([-np.inf if v is None else v for v in head["lower"]])
upper = np.array([np.inf if v is None else v for v in head["upper"]])
cache = {"x": None, "r": None, "j": None}
wait = [0.0, 0]


def read_exact(k):
    buf = bytearray()
    while len(buf) < k:
        chunk = inp.read(k - len(buf))
        if not chunk:
            raise EOFError("parent closed the pipe")
        buf += chunk
    return bytes(buf)


def evaluate(x):
    if cache["x"] is not None and np.array_equal(cache["x"], x):
        return
    t = time.perf_counter()
    out.write(b"E" + np.asarray(x, dtype="<f8").tobytes())
    out.flush()
    r = np.frombuffer(read_exact(8 * m), dtype="<f8")
    j = np.frombuffer(read_exact(8 * m * n), dtype="<f8").reshape(m, n)
    wait[0] += time.perf_counter() - t
    wait[1] += 1
    cache.update(x=np.array(x, copy=True), r=r, j=j)


def fun(x):
    evaluate(x)
    return cache["r"]


def jac(x):
    evaluate(x)
    return cache["j"]


# the solve `runs` times from the same start (the best of them is the figure, as for metrocell's)
runs = int(head.get("runs", 1))
seconds, waits = [], []
for _ in range(runs):
    cache.update(x=None, r=None, j=None)
    wait[0], wait[1] = 0.0, 0
    t0 = time.perf_counter()
    sol = least_squares(fun, x0, jac=jac, method="trf", bounds=(lower, upper), x_scale="jac", ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=200)
    seconds.append(time.perf_counter() - t0)
    waits.append(wait[0])
out.write(b"D" + json.dumps({"x": sol.x.tolist(), "seconds": seconds, "evaluation_seconds": waits, "evaluations": wait[1], "nfev": int(sol.nfev), "njev": int(sol.njev or 0), "status": int(sol.status), "cost": float(sol.cost)}).encode() + b"\n")
out.flush()
