"""Reference solutions from scipy.optimize.least_squares (method "trf", analytic Jacobian).

Reads from stdin: line 1 the problem name, line 2 the start x0, line 3 lower bounds, line 4
upper bounds (inf allowed), line 5 the problem's data (flat, whitespace-separated). Writes the
solution (one line), then "seconds <wall time of least_squares>" and "nfev <n> njev <n>".
The residuals and Jacobians are the same as the Rust tests' and the benchmark's (see there).
"""
import sys
import time

import numpy as np
from numpy.polynomial import legendre
from scipy.optimize import least_squares


def rosenbrock(_data):
    f = lambda x: np.array([10.0 * (x[1] - x[0] ** 2), 1.0 - x[0]])
    j = lambda x: np.array([[-20.0 * x[0], 10.0], [-1.0, 0.0]])
    return f, j


def decay(data):
    t, y = data.reshape(2, -1)

    def f(x):
        return x[0] + x[1] * (1.0 - np.exp(-t / x[2])) - y

    def j(x):
        e = np.exp(-t / x[2])
        return np.column_stack([np.ones_like(t), 1.0 - e, -x[1] * e * t / x[2] ** 2])

    return f, j


def circle(data):
    px, py = data.reshape(2, -1)

    def f(x):
        return np.hypot(px - x[0], py - x[1]) - x[2]

    def j(x):
        d = np.hypot(px - x[0], py - x[1])
        return np.column_stack([-(px - x[0]) / d, -(py - x[1]) / d, -np.ones_like(d)])

    return f, j


def xfyz(data):
    """Quasi-XFYZ benchmark: measured = Rz(γ)Ry(β)Rx(α)·(q + E(q)·p) + t, see examples/solver_benchmark.rs."""
    qm = data.reshape(-1, 6)
    q, meas = qm[:, :3], qm[:, 3:]
    n = len(q)
    u = 2.0 * q - 1.0
    # Legendre values P_k(u_a) for k = 0..8, axis a: shape (n, 3, 9).
    vander = np.stack([legendre.legvander(u[:, a], 8) for a in range(3)], axis=1)
    # Design E (n, 3, 64): coordinate c gets, from axis a, degrees 1..7 if c == a else 2..8;
    # the last column is the twist q_x·q_y in z.
    cols = []
    for c in range(3):
        for a in range(3):
            ks = range(1, 8) if c == a else range(2, 9)
            for k in ks:
                col = np.zeros((n, 3))
                col[:, c] = vander[:, a, k]
                cols.append(col)
    col = np.zeros((n, 3))
    col[:, 2] = q[:, 0] * q[:, 1]
    cols.append(col)
    E = np.stack(cols, axis=2)

    def rot(x):
        a, b, g = x[64], x[65], x[66]
        ca, sa, cb, sb, cg, sg = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(g), np.sin(g)
        rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
        ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
        rz = np.array([[cg, -sg, 0], [sg, cg, 0], [0, 0, 1]])
        drx = np.array([[0, 0, 0], [0, -sa, -ca], [0, ca, -sa]])
        dry = np.array([[-sb, 0, cb], [0, 0, 0], [-cb, 0, -sb]])
        drz = np.array([[-sg, -cg, 0], [cg, -sg, 0], [0, 0, 0]])
        return rz @ ry @ rx, [rz @ ry @ drx, rz @ dry @ rx, drz @ ry @ rx]

    def f(x):
        r, _ = rot(x)
        p = q + E @ x[:64]
        return (p @ r.T + x[67:70] - meas).ravel()

    def j(x):
        r, dr = rot(x)
        p = q + E @ x[:64]
        jac = np.empty((n, 3, 70))
        jac[:, :, :64] = np.einsum("ij,njk->nik", r, E)
        for k in range(3):
            jac[:, :, 64 + k] = p @ dr[k].T
        jac[:, :, 67:70] = np.eye(3)
        return jac.reshape(3 * n, 70)

    return f, j


PROBLEMS = {"rosenbrock": rosenbrock, "decay": decay, "circle": circle, "xfyz": xfyz}


def main():
    lines = sys.stdin.read().split("\n")
    name = lines[0].strip()
    x0, lo, hi = (np.array([float(v) for v in lines[i].split()]) for i in (1, 2, 3))
    data = np.array([float(v) for v in lines[4].split()]) if len(lines) > 4 else np.array([])
    f, j = PROBLEMS[name](data)
    tol = 1e-15 if name != "xfyz" else 1e-12
    start = time.perf_counter()
    res = least_squares(f, x0, jac=j, bounds=(lo, hi), method="trf", xtol=tol, ftol=tol, gtol=tol)
    seconds = time.perf_counter() - start
    print(" ".join(repr(float(v)) for v in res.x))
    print(f"seconds {seconds}")
    print(f"nfev {res.nfev} njev {res.njev} status {res.status}")


if __name__ == "__main__":
    main()
