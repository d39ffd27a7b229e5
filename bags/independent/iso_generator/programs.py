"""Measurement programs: which points, in which order, when, and what the controller knew.

A `Planner` walks the machine through a program the way an operator's job would: moves at a
feed (plus a fixed acceleration overhead), settles, and the tracker takes a reading (its time
stamp at the end of its own averaging); some points are read more than once; sweeps read on the
fly at a constant feed. It keeps every commanded position the axes went through (targets,
overruns, parking), so approach directions come from the real path (ISO 230-2: the direction of
the last motion before the target).

Point sets are our own: random points in the volume, ISO 230-2 style irregular target positions
along lines (so a periodic screw error does not alias onto an even pitch), body diagonals
(ISO 230-6), irregular grids.
"""

import numpy as np

from .reversal import approach_directions


class Planner:
    def __init__(self, home, rng, feed_m_s=0.08, accel_overhead_s=0.6, settle_s=(1.0, 2.5), read_s=(0.8, 1.5), t0_s=0.0):
        self.rng = rng
        self.feed, self.overhead = feed_m_s, accel_overhead_s
        self.settle, self.read = settle_s, read_s
        self.t = t0_s
        self.q = np.asarray(home, dtype=float)
        self.path = [self.q.copy()]
        self.rows = []          # dicts: t, q, v, path_index, point_id, role, nominal_override

    # -- motion -------------------------------------------------------------------------------
    def move_to(self, q, feed=None):
        q = np.asarray(q, dtype=float)
        dist = float(np.max(np.abs(q - self.q)))       # axes move together, the longest governs
        if dist > 0:
            self.t += dist / (feed or self.feed) + self.overhead
            self.q = q.copy()
            self.path.append(self.q.copy())

    def pause(self, seconds):
        self.t += seconds

    # -- readings -----------------------------------------------------------------------------
    def read_here(self, point_id, repeats=1, role="fit"):
        """Settle, then `repeats` readings ~1 s apart at the current position."""
        self.t += self.rng.uniform(*self.settle)
        for _ in range(repeats):
            self.t += self.rng.uniform(*self.read)
            self.rows.append({"t": self.t, "q": self.q.copy(), "v": np.zeros(3), "path_index": len(self.path) - 1,
                              "point_id": point_id, "role": role, "nominal": None})

    def read_nest(self, nest_id, nest_position, repeats=2):
        """The operator takes the SMR off the spindle and puts it in a reference nest fixed on
        the table while the machine stands where it stopped: the reading has the nest's
        calibrated coordinates as nominal, and the controller still logs its (parked) axes."""
        self.t += self.rng.uniform(8.0, 20.0)             # walk the SMR to the nest
        for _ in range(repeats):
            self.t += self.rng.uniform(*self.read)
            self.rows.append({"t": self.t, "q": self.q.copy(), "v": np.zeros(3), "path_index": len(self.path) - 1,
                              "point_id": nest_id, "role": "reference", "nominal": np.asarray(nest_position, dtype=float)})

    def sweep(self, q_from, q_to, feed, interval_s, id_prefix):
        """Move to q_from, then traverse to q_to at a constant feed, the tracker reading every
        `interval_s` on the fly (readings in the constant-velocity part only)."""
        self.move_to(q_from)
        self.t += self.rng.uniform(0.3, 0.8)
        q_from, q_to = np.asarray(q_from, float), np.asarray(q_to, float)
        length = float(np.linalg.norm(q_to - q_from))
        v = (q_to - q_from) / length * feed
        t_start = self.t + self.overhead / 2              # after the acceleration ramp
        duration = length / feed
        times = np.arange(t_start + self.rng.uniform(0, interval_s), t_start + duration - self.overhead / 2, interval_s)
        for k, tk in enumerate(times):
            qk = q_from + v * (tk - t_start)
            self.path.append(qk.copy())
            self.rows.append({"t": tk, "q": qk, "v": v.copy(), "path_index": len(self.path) - 1,
                              "point_id": f"{id_prefix}.{k:03d}", "role": "fit", "nominal": None})
        self.t = t_start + duration + self.overhead / 2
        self.q = q_to.copy()
        self.path.append(self.q.copy())

    # -- result -------------------------------------------------------------------------------
    def readings(self):
        path = np.array(self.path)
        approach = approach_directions(path, [r["path_index"] for r in self.rows])
        out = {
            "t": np.array([r["t"] for r in self.rows]),
            "q": np.array([r["q"] for r in self.rows]),
            "v": np.array([r["v"] for r in self.rows]),
            "approach": approach,
            "point_id": [r["point_id"] for r in self.rows],
            "role": np.array([r["role"] for r in self.rows]),
            "nest": [r["nominal"] for r in self.rows],
            "is_nest": np.array([r["nominal"] is not None for r in self.rows]),
        }
        moving = np.linalg.norm(out["v"], axis=1) > 0
        # an axis moving at the reading approaches in its direction of motion
        out["approach"] = np.where(np.abs(out["v"]) > 0, np.sign(out["v"]), out["approach"])
        out["moving"] = moving
        return out


# -- point sets -------------------------------------------------------------------------------

def random_points(travel, n, rng, margin=0.02):
    lo = np.array([a for a, _ in travel]) + margin
    hi = np.array([b for _, b in travel]) - margin
    return np.round(rng.uniform(lo, hi, size=(n, 3)), 4)          # 0.1 mm, as an operator types them


def irregular_targets(lo, hi, n, rng):
    """ISO 230-2 (2014) 4.3.2: target positions spread over the travel with unequal intervals,
    "to cover the periodic errors": an even pitch plus a random offset of up to ±30 % of it."""
    pitch = (hi - lo) / (n - 1)
    base = lo + pitch * np.arange(n)
    jitter = rng.uniform(-0.3, 0.3, n) * pitch
    jitter[0], jitter[-1] = abs(jitter[0]) * 0.2, -abs(jitter[-1]) * 0.2
    return np.round(np.clip(base + jitter, lo, hi), 4)


def body_diagonal_points(travel, n, rng, corner_from, corner_to, margin=0.02):
    lo = np.array([a for a, _ in travel]) + margin
    hi = np.array([b for _, b in travel]) - margin
    a = np.where(np.asarray(corner_from) > 0, hi, lo)
    b = np.where(np.asarray(corner_to) > 0, hi, lo)
    s = np.sort(rng.uniform(0.0, 1.0, n))
    return np.round(a + np.outer(s, b - a), 4)


# -- programs ---------------------------------------------------------------------------------

def bidirectional_lines(planner, travel, axis, lines, n_targets, runs, rng, overrun=0.004, repeats=(1, 2)):
    """ISO 230-2 standard test cycle along `axis` on each line (fixed other coordinates): runs
    forward (approaching every target moving +) and back (moving −), with an overrun past the
    last target so the reversal happens outside the measured positions."""
    k = "xyz".index(axis)
    lo, hi = travel[k]
    targets = irregular_targets(lo + 0.01, hi - 0.01, n_targets, rng)
    for li, fixed in enumerate(lines):
        for run in range(runs):
            for direction in (+1, -1):
                order = targets if direction > 0 else targets[::-1]
                start = np.array(fixed, dtype=float)
                start[k] = order[0] - direction * overrun
                planner.move_to(start)
                for ti, x in enumerate(order):
                    q = np.array(fixed, dtype=float)
                    q[k] = x
                    planner.move_to(q)
                    idx = int(np.where(targets == x)[0][0])
                    planner.read_here(f"L{axis.upper()}{li + 1}.{idx + 1:02d}", repeats=int(rng.integers(repeats[0], repeats[1] + 1)))
                end = np.array(fixed, dtype=float)
                end[k] = order[-1] + direction * overrun
                planner.move_to(end)


def random_rounds(planner, points, rounds, rng, round_gap_s=(60, 240), repeat_probability=0.3, id_prefix="P",
                  nests=None, nest_every_s=1800.0):
    """Each round visits every point once in a new random order; rounds start at irregular
    intervals; a third of the readings are repeated (the operator's habit of "shooting twice").
    With `nests`, the reference nests are re-measured every ~nest_every_s (between points)."""
    next_nest = planner.t
    for r in range(rounds):
        for i in rng.permutation(len(points)):
            if nests is not None and planner.t >= next_nest:
                for nid, npos in nests:
                    planner.read_nest(nid, npos)
                next_nest = planner.t + nest_every_s * rng.uniform(0.85, 1.15)
            planner.move_to(points[i])
            planner.read_here(f"{id_prefix}{i + 1:03d}", repeats=2 if rng.random() < repeat_probability else 1)
        planner.pause(rng.uniform(*round_gap_s))
    if nests is not None:
        for nid, npos in nests:
            planner.read_nest(nid, npos)


def serpentine_grid(planner, xs, ys, zs, id_prefix="G", repeats=1):
    """An irregular grid visited serpentine in X (every X position approached from both sides
    over the Y rows), Y rows alternating per Z level."""
    for iz, z in enumerate(zs):
        yy = ys if iz % 2 == 0 else ys[::-1]
        for iy, y in enumerate(yy):
            xx = xs if (iy + iz) % 2 == 0 else xs[::-1]
            for x in xx:
                planner.move_to([x, y, z])
                ix = int(np.where(xs == x)[0][0])
                jy = int(np.where(ys == y)[0][0])
                planner.read_here(f"{id_prefix}{ix + 1:02d}{jy + 1:02d}{iz + 1:02d}", repeats=repeats)


def shift_schedule(rounds_fn, planner, duration_s, rng, gap_s=(5 * 60, 18 * 60)):
    """Repeat `rounds_fn(planner)` with irregular pauses until the shift's end (thermal and
    instrument cases: 2–6 h)."""
    while planner.t < duration_s:
        rounds_fn(planner)
        planner.pause(rng.uniform(*gap_s))
