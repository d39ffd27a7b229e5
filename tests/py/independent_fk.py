"""Forward kinematics written from the sources, not from metrocell's code: the reference the
`independent_kinematics` test compares the twin and crates/kinematics with.

- five_axis: seed 004 (`shared/seeds/004_five_axis_model.md`, the project notes kept outside this repository), the linear axes by the
  reconstructed DH table (the printed table has its a/alpha headers swapped: digest section 2.1),
  standard DH A = Rz(theta) Tz(d) Tx(a) Rx(alpha); the table/table rotary axes as the digest's
  section 6.1 item 2 extends it: p_machine = Trans(b_pivot) Ry(B) Trans(c_offset) Rz(C)
  Trans(workpiece_offset) p_workpiece.
- delta: seed 002 / Marlin: towers at 210, 330, 90 degrees (+ angle trim), radius R + trim, rod D +
  trim; the firmware inverts the nominal geometry (DELTA_IK), the carriages then sit where the
  true geometry's trilateration puts the effector; endstop e: physical carriage = count + e.
- ur5: Universal Robots' published DH parameters of the UR5 (standard DH), hard-coded here.

Reads one JSON object on stdin (the cells as JSON, joint vectors), prints one JSON object.
Quantities in the cells are numbers (SI) or text with a unit ("250 mm", "30 deg").
"""

import json
import math
import sys

import numpy as np

UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "cm": 1e-2, "rad": 1.0, "deg": math.pi / 180.0, "urad": 1e-6, "mrad": 1e-3}


def si(q):
    if isinstance(q, (int, float)):
        return float(q)
    value, unit = q.split()
    return float(value) * UNITS[unit]


def vec(v):
    return np.array([si(x) for x in v]) if v is not None else np.zeros(3)


def dh(theta, d, a, alpha):
    """Standard DH link transform Rz(theta) Tz(d) Tx(a) Rx(alpha), written out."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array([
        [ct, -st * ca, st * sa, a * ct],
        [st, ct * ca, -ct * sa, a * st],
        [0.0, sa, ca, d],
        [0.0, 0.0, 0.0, 1.0],
    ])


def trans(v):
    t = np.eye(4)
    t[:3, 3] = v
    return t


def rot_y(b):
    c, s = math.cos(b), math.sin(b)
    return np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1.0]])


def rot_z(c_):
    c, s = math.cos(c_), math.sin(c_)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def five_axis(cell, joints):
    g = cell["machine"]["five_axis"]
    d0, tool = si(g["d0"]), si(g["tool_length"])
    deg = math.pi / 180.0
    out = []
    for X, Y, Z, B, C in joints:
        # cell joint vector [X, Y, Z, B, C]: X = d2, Y = d1, Z = -d3
        d1, d2, d3 = Y, X, -Z
        t = np.eye(4)
        for row in [(90 * deg, d0, 0.0, 0.0), (0.0, 0.0, d1, 90 * deg), (-90 * deg, d2, 0.0, -90 * deg), (0.0, 0.0, d3, 0.0)]:
            t = t @ dh(*row)
        # paper eq. 1: (x, y, z) = (d2, d1, d0 - d3)
        assert np.allclose(t[:3, 3], [d2, d1, d0 - d3], atol=1e-15), t
        tool_dir = t[:3, 0]  # the tool points along frame 4's x axis (machine -z)
        assert np.allclose(tool_dir, [0, 0, -1], atol=1e-15), tool_dir
        tip_machine = t[:3, 3] + tool * tool_dir
        m_from_w = trans(vec(g.get("b_pivot"))) @ rot_y(B) @ trans(vec(g.get("c_offset"))) @ rot_z(C) @ trans(vec(g.get("workpiece_offset")))
        w = np.linalg.inv(m_from_w)
        tip = w[:3, :3] @ tip_machine + w[:3, 3]
        axis = w[:3, :3] @ -tool_dir
        out.append({"tip": tip.tolist(), "axis": axis.tolist()})
    return out


def delta(cell, points):
    d = cell["machine"]["delta"]
    D, R = si(d["rod_length"]), si(d["radius"])
    tool = vec(cell["machine"].get("tool_offset"))
    trims = {"rod_length": [0.0] * 3, "radius": [0.0] * 3, "angle": [0.0] * 3, "endstop": [0.0] * 3}
    for term in cell.get("terms", []):
        prefix = {"delta_rod_length": "rod_length", "delta_radius": "radius", "delta_tower_angle": "angle", "delta_endstop": "endstop"}[term["id"]]
        for k, tower in enumerate("abc"):
            trims[prefix][k] = si(term["params"].get(f"{prefix}_{tower}", 0))
    base = [210.0, 330.0, 90.0]

    def towers(radius_trim, angle_trim):
        return [np.array([(R + radius_trim[k]) * math.cos(math.radians(base[k]) + angle_trim[k]), (R + radius_trim[k]) * math.sin(math.radians(base[k]) + angle_trim[k])]) for k in range(3)]

    nominal = towers([0.0] * 3, [0.0] * 3)
    true = towers(trims["radius"], trims["angle"])
    rods = [D + trims["rod_length"][k] for k in range(3)]
    out = []
    for p in points:
        p = np.array(p)
        # firmware: DELTA_IK on the nominal geometry, no endstop offsets
        q = [p[2] + math.sqrt(D * D - (nominal[k][0] - p[0]) ** 2 - (nominal[k][1] - p[1]) ** 2) for k in range(3)]
        # true carriage joints; the effector is the lower intersection of three spheres
        c = [np.array([true[k][0], true[k][1], q[k] + trims["endstop"][k]]) for k in range(3)]
        ex = (c[1] - c[0]) / np.linalg.norm(c[1] - c[0])
        i = ex @ (c[2] - c[0])
        ey = c[2] - c[0] - i * ex
        ey /= np.linalg.norm(ey)
        ez = np.cross(ex, ey)
        dd = np.linalg.norm(c[1] - c[0])
        j = ey @ (c[2] - c[0])
        x = (rods[0] ** 2 - rods[1] ** 2 + dd * dd) / (2 * dd)
        y = (rods[0] ** 2 - rods[2] ** 2 + i * i + j * j) / (2 * j) - i * x / j
        z = math.sqrt(rods[0] ** 2 - x * x - y * y)
        cands = [c[0] + x * ex + y * ey + s * z * ez for s in (1, -1)]
        e = min(cands, key=lambda v: v[2])
        for k in range(3):
            assert abs(np.linalg.norm(e - c[k]) - rods[k]) < 1e-12
        out.append((e + tool).tolist())
    return out


# UR5, Universal Robots' published DH (standard convention): d, a, alpha per joint.
UR5_DH = [(0.089159, 0.0, math.pi / 2), (0.0, -0.425, 0.0), (0.0, -0.39225, 0.0), (0.10915, 0.0, math.pi / 2), (0.09465, 0.0, -math.pi / 2), (0.0823, 0.0, 0.0)]


def pose(section):
    t = np.eye(4)
    if section is None:
        return t
    e = [si(a) for a in section.get("euler_xyz", [0, 0, 0])]
    rx = np.array([[1, 0, 0], [0, math.cos(e[0]), -math.sin(e[0])], [0, math.sin(e[0]), math.cos(e[0])]])
    ry = rot_y(e[1])[:3, :3]
    rz = rot_z(e[2])[:3, :3]
    t[:3, :3] = rx @ ry @ rz
    t[:3, 3] = vec(section.get("translation"))
    return t


def ur5(cell, joints):
    arm = cell["machine"]["serial_arm"]
    base, tool = pose(arm.get("base")), pose(arm.get("tool"))
    out = []
    for q in joints:
        t = base.copy()
        for (d, a, alpha), qi in zip(UR5_DH, q):
            t = t @ dh(qi, d, a, alpha)
        out.append((t @ tool)[:3, 3].tolist())
    return out


def main():
    req = json.load(sys.stdin)
    out = {}
    if "five_axis" in req:
        out["five_axis"] = five_axis(req["five_axis"]["cell"], req["five_axis"]["joints"])
    if "delta" in req:
        out["delta"] = delta(req["delta"]["cell"], req["delta"]["points"])
    if "ur5" in req:
        out["ur5"] = ur5(req["ur5"]["cell"], req["ur5"]["joints"])
    # seed 004 digest K1: FK(d0 = 0, d1 = 228, d2 = 308, d3 = 140 mm) = (308, 228, -140) mm
    k1 = five_axis({"machine": {"five_axis": {"d0": 0, "tool_length": 0}}}, [[0.308, 0.228, -0.140, 0.0, 0.0]])[0]["tip"]
    assert np.allclose(k1, [0.308, 0.228, -0.140], atol=1e-15), k1
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
