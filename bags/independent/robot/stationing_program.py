"""The stationing program: waypoints in groups, each group's 8 fit points and ~40 check points,
the groups measured from a few instrument setups around the robot.

* column heights: 3–5 levels of column_lower spread over 0.02…0.58 m;
* setups: 3–5 (the instrument moved 2–4 times), spread around the robot, each measuring 2–3
  consecutive groups; a group is measured from one setup;
* a group: one column height, two of the arm's four solution spaces (elbow up/down × wrist
  flipped or not), the arm working on the instrument's side (shoulder_pan within ±75° of the
  direction to the instrument: the prism stays in sight); 8 fit points chosen spread (the
  farthest-point rule over the prism's positions, four per solution space), the rest checks;
* a waypoint is valid when the prism is ≥ 0.3 m above the ground and ≥ 0.4 m from the column's
  axis, the wrist and elbow clear of the column (≥ 0.3 m from its axis wherever below its top);
* timing: each waypoint is a move (5–12 s), a dwell (3 s) and the measurement (2 s); moving
  the instrument takes 12–20 min.

The program (joints, roles, which setup measures which group, the side each setup stands on)
is the same on every ground — one plan, repeated; where exactly each setup stands (distance,
height, its yaw) differs per recording.
"""

import numpy as np

from robot_description import ARM_JOINTS
from true_robot import nominal_prism

BRANCHES = [("elbow_up", +1), ("elbow_up", -1), ("elbow_down", +1), ("elbow_down", -1)]


def _sample_branch(rng, n, branch, pan_centre):
    elbow, wrist = branch
    q = {"shoulder_pan": pan_centre + rng.uniform(-np.radians(90), np.radians(90), n)}
    if elbow == "elbow_up":
        q["shoulder_lift"] = rng.uniform(-1.45, -0.25, n)
        q["elbow"] = rng.uniform(0.5, 2.4, n)
    else:
        q["shoulder_lift"] = rng.uniform(-0.5, 0.7, n)
        q["elbow"] = rng.uniform(-2.4, -0.6, n)
    q["wrist_1"] = rng.uniform(-2.6, 1.0, n)
    q["wrist_2"] = wrist * rng.uniform(0.35, 2.8, n)
    q["wrist_3"] = rng.uniform(-np.pi, np.pi, n)
    return q


def _valid(urdf, q):
    frames, _ = urdf.forward(urdf.full_joint_values(q))
    axis_xy = frames["column_outer"][0, :2, 3]
    top_z = frames["column_top"][:, 2, 3]
    prism = frames["prism"][:, :3, 3]
    ok = (prism[:, 2] > 0.3) & (np.hypot(*(prism[:, :2] - axis_xy).T) > 0.4)
    for link in ("forearm_link", "wrist_1_link", "wrist_2_link"):
        p = frames[link][:, :3, 3]
        r = np.hypot(*(p[:, :2] - axis_xy).T)
        ok &= (r > 0.3) | (p[:, 2] > top_z + 0.05)
        ok &= p[:, 2] > 0.35
    return ok


def _valid_waypoints(rng, urdf, branch, pan_centre, column_lower, need):
    """`need` valid arm configurations of one solution space (drawn until enough are valid)."""
    got = {j: np.empty(0) for j in ARM_JOINTS}
    while len(got["elbow"]) < need:
        cand = _sample_branch(rng, 4 * need, branch, pan_centre)
        cand["column_lower"] = np.full(4 * need, column_lower)
        ok = _valid(urdf, cand)
        for j in ARM_JOINTS:
            got[j] = np.concatenate([got[j], cand[j][ok]])
    return {j: got[j][:need] for j in ARM_JOINTS}


def _farthest_points(points, k, rng):
    chosen = [int(rng.integers(len(points)))]
    d = np.linalg.norm(points - points[chosen[0]], axis=1)
    while len(chosen) < k:
        i = int(np.argmax(d))
        chosen.append(i)
        d = np.minimum(d, np.linalg.norm(points - points[i], axis=1))
    return chosen


def make_program(rng, urdf, target_waypoints=450, n_groups=None):
    """{q {independent joint: (N,)}, group (N,), role (N,), branch (N,), level (N,), setup_of_group,
    setup_azimuths_rad, groups: [...]}."""
    n_levels = int(rng.integers(3, 6))
    levels = np.round(np.linspace(0.02, 0.58, n_levels), 3)
    n_groups = int(rng.choice([9, 10])) if n_groups is None else n_groups
    setup_of_group, azimuths = setup_plan(rng, n_groups)
    per_group = target_waypoints // n_groups
    level_seq = np.concatenate([rng.permutation(n_levels) for _ in range(n_groups // n_levels + 1)])[:n_groups]
    rows = {j: [] for j in ("column_lower",) + ARM_JOINTS}
    group, role, branch_of, level_of = [], [], [], []
    groups = []
    for g in range(n_groups):
        size = per_group + int(rng.integers(-2, 3))
        # the arm works on its setup's side (at pan = 0 it reaches along the base's +x)
        pan_centre = _wrap(azimuths[setup_of_group[g]] + rng.uniform(-0.4, 0.4))
        pair = rng.choice(len(BRANCHES), 2, replace=False)
        q_parts, b_parts = [], []
        for bi, b in enumerate(pair):
            need = size // 2 + (size % 2 if bi == 0 else 0)
            q_parts.append(_valid_waypoints(rng, urdf, BRANCHES[b], pan_centre, levels[level_seq[g]], need))
            b_parts.append(np.full(need, b))
        q = {j: np.concatenate([p[j] for p in q_parts]) for j in ARM_JOINTS}
        br = np.concatenate(b_parts)
        q["column_lower"] = np.full(len(br), levels[level_seq[g]])
        # fit points: spread over the prism's positions, four per solution space
        prism = nominal_prism(urdf, q)
        fit = []
        for b in pair:
            idx = np.flatnonzero(br == b)
            fit += list(idx[_farthest_points(prism[idx], 4, rng)])
        order = rng.permutation(len(br))
        r = np.array(["check"] * len(br), dtype=object)
        r[fit] = "fit"
        for j in rows:
            rows[j].append(q[j][order])
        group += [g] * len(br)
        role += list(r[order])
        branch_of += list(br[order])
        level_of += [level_seq[g]] * len(br)
        groups.append({"index": g, "column_lower_m": float(levels[level_seq[g]]),
                       "branches": [BRANCHES[b][0] + ("_wrist+" if BRANCHES[b][1] > 0 else "_wrist-") for b in pair],
                       "pan_centre_rad": float(pan_centre), "waypoints": int(len(br)), "setup": f"S{setup_of_group[g] + 1}"})
    q = {j: np.concatenate(v) for j, v in rows.items()}
    return {"q": q, "group": np.array(group), "role": np.array(role), "branch": np.array(branch_of),
            "level": np.array(level_of), "levels_m": levels.tolist(), "groups": groups, "n_groups": n_groups,
            "setup_of_group": setup_of_group, "setup_azimuths_rad": azimuths}


def setup_plan(rng, n_groups):
    """Which setup measures which group: 3–5 setups, consecutive groups, as even as possible,
    and the directions of the setups from the robot (spread around it)."""
    n_setups = int(rng.integers(3, 6))
    sizes = np.full(n_setups, n_groups // n_setups)
    sizes[: n_groups % n_setups] += 1
    of_group = np.repeat(np.arange(n_setups), sizes)
    a0 = rng.uniform(0, 2 * np.pi)
    azimuths = a0 + 2 * np.pi * np.arange(n_setups) / n_setups + rng.uniform(-0.3, 0.3, n_setups)
    return of_group, azimuths


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def timing(rng, program, setup_of_group, start_s=0.0):
    """Seconds since the recording's start at which each waypoint was measured."""
    t, out = start_s, np.zeros(len(program["group"]))
    last_setup = None
    for g in range(program["n_groups"]):
        if last_setup is not None and setup_of_group[g] != last_setup:
            t += rng.uniform(12 * 60, 20 * 60)     # moving and levelling the instrument
        last_setup = setup_of_group[g]
        t += rng.uniform(30, 60)                   # the column moving to the group's height
        for i in np.flatnonzero(program["group"] == g):
            t += rng.uniform(5, 12) + 3.0 + 2.0
            out[i] = t
    return out
