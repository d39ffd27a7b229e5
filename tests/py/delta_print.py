"""A linear delta printer running Marlin, simulated from Marlin's own definitions, not by
metrocell: towers at 210/330/90 degrees plus M665 X/Y/Z trims, DELTA_IK
q_T = z + sqrt(rod_T^2 - |tower_T - p|^2), homing as homeaxis() does it (each carriage rises to
its switch, moves by its M666 adjustment, and is counted where IK puts the effector centred at
M665 H), and the nozzle found by Newton's method on the three rod constraints (metrocell
trilaterates in closed form).

The physical printer differs from its settings: rod 1 mm longer than M665 L, tower A turned
0.5 deg, radius 0.4 mm larger, switches at different heights (DELTA_PRINTER=other in the
environment: rod 0.7 mm shorter, radius 0.5 mm smaller, towers A -0.4 and B +0.25 deg). The calibration star — features
at the centre and along 12 directions at 25, 50 and 75 mm, printed 0.2 mm above the bed — is
"photographed" in the object's own frame (turned and shifted on the bed, Gaussian noise of
sigma per axis); with --heights, the bed is probed at 19 points (noise sigma/2); with --bars, the
three 75 mm bars from the centre toward the towers are measured with a caliper (sigma 0.01 mm).

Settings are used as the printer runs them after the user's paper test (M665 H set so the
nozzle touches the bed's centre at Z0); the settings file is not rewritten.

usage:
  delta_print.py print SETTINGS.gcode OUT.csv SIGMA_MM SEED [--heights] [--bars]
      writes the measurements `metrocell delta fit` reads
  delta_print.py check SETTINGS.gcode
      prints, for a printer running these settings, the largest plan error of the printed star
      after its best rigid fit (mm), the largest bar-length error (mm) and the largest height
      error over the bed (mm)
"""
import os
import re
import sys

import numpy as np

BASE_DEG = np.array([210.0, 330.0, 90.0])

# the physical printer. DELTA_PRINTER=other picks one whose errors have the other signs and
# other sizes (rod 0.7 mm short, radius 0.5 mm small, tower A -0.4 deg and B +0.25 deg, C's
# switch the highest), so a fit that only works for one sign of each error fails there.
PRINTERS = {
    "default": (216.0, 106.0, [0.5, 0.0, 0.0], [437.6, 438.2, 437.3]),
    "other": (214.3, 105.1, [-0.4, 0.25, 0.0], [437.1, 436.5, 438.4]),
}
_rod, _radius, _trims, _switch = PRINTERS[os.environ.get("DELTA_PRINTER", "default")]
TRUE_ROD = _rod
TRUE_RADIUS = _radius
TRUE_ANGLE_DEG = BASE_DEG + np.array(_trims)
SWITCH = np.array(_switch)  # carriage height where each switch trips (mm)


def parse_settings(path):
    """M665/M666 words from a file of G-code (M503's echo lines work too)."""
    s = {"L": 215.0, "R": 105.6, "H": 250.0, "X": 0.0, "Y": 0.0, "Z": 0.0,
         "A": 0.0, "B": 0.0, "C": 0.0, "EX": 0.0, "EY": 0.0, "EZ": 0.0}
    for line in open(path):
        line = line.split(";")[0]
        m = re.search(r"\bM66([56])\b(.*)", line)
        if not m:
            continue
        words = re.findall(r"([A-Z])\s*(-?[0-9.]+)", m.group(2))
        # Marlin 1.1 echoes its calibration radius as M665 B; 2.x's B is tower B's rod trim,
        # echoed with A and C
        trims = any(letter in "AC" for letter, _ in words)
        for letter, value in words:
            if m.group(1) == "5" and letter == "B" and not trims:
                continue
            key = letter if m.group(1) == "5" else "E" + letter
            if key in s:
                s[key] = float(value)
    return paper_test(s)


def paper_test(s):
    """What a user does after loading settings and before printing: M665 H raised or lowered until
    the nozzle touches the bed at its centre at Z0 (a higher H counts every carriage higher, so
    the same commands put the nozzle lower by as much)."""
    s = dict(s)
    s["H"] += printed(s, np.array([0.0, 0.0, 0.0]))[2]
    return s


def firmware_towers(s):
    ang = np.radians(BASE_DEG + np.array([s["X"], s["Y"], s["Z"]]))
    xy = s["R"] * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    rods = s["L"] + np.array([s["A"], s["B"], s["C"]])
    return xy, rods


def ik(xy, rods, p):
    d2 = ((xy - p[:2]) ** 2).sum(axis=1)
    return p[2] + np.sqrt(rods**2 - d2)


def homed_offsets(s):
    """Physical carriage height minus the firmware's count, after G28."""
    xy, rods = firmware_towers(s)
    count = ik(xy, rods, np.array([0.0, 0.0, s["H"]]))
    adj = np.array([s["EX"], s["EY"], s["EZ"]])
    return SWITCH + adj - count


TRUE_XY = TRUE_RADIUS * np.stack([np.cos(np.radians(TRUE_ANGLE_DEG)), np.sin(np.radians(TRUE_ANGLE_DEG))], axis=1)


def nozzle(carriages):
    """The nozzle below carriages at these physical heights: Newton on |p - c_T| = rod."""
    c = np.column_stack([TRUE_XY, carriages])
    p = np.array([0.0, 0.0, carriages.mean() - TRUE_ROD * 0.8])
    for _ in range(50):
        d = p - c
        f = (d**2).sum(axis=1) - TRUE_ROD**2
        step = np.linalg.solve(2.0 * d, f)
        p = p - step
        if np.abs(step).max() < 1e-13:
            break
    return p


def printed(s, p):
    xy, rods = firmware_towers(s)
    return nozzle(ik(xy, rods, p) + homed_offsets(s))


def star():
    pts = [np.array([0.0, 0.0, 0.2])]
    for k in range(12):
        a = np.radians(30.0 * k + 90.0)
        for r in (10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0):
            pts.append(np.array([r * np.cos(a), r * np.sin(a), 0.2]))
    return pts


def probe_points():
    pts = [np.array([0.0, 0.0, 0.0])]
    for k in range(6):
        a = np.radians(60.0 * k + 90.0)
        for r in (35.0, 70.0):
            pts.append(np.array([r * np.cos(a), r * np.sin(a), 0.0]))
    for k in range(6):
        a = np.radians(60.0 * k + 120.0)
        pts.append(np.array([52.0 * np.cos(a), 52.0 * np.sin(a), 0.0]))
    return pts


def print_star(settings, out, sigma, seed, heights, bars):
    s = parse_settings(settings)
    rng = np.random.default_rng(seed)
    turn = rng.uniform(-np.pi, np.pi)
    rot = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    shift = rng.uniform(-30.0, 30.0, 2)
    with open(out, "w") as f:
        f.write("kind,x_mm,y_mm,z_mm,to_x_mm,to_y_mm,to_z_mm,measured_x_mm,measured_y_mm,measured_mm,sigma_mm\n")
        for c in star():
            m = rot @ printed(s, c)[:2] + shift + rng.normal(0.0, sigma, 2)
            f.write(f"plan,{c[0]:.4f},{c[1]:.4f},{c[2]:.4f},,,,{m[0]:.5f},{m[1]:.5f},,{sigma}\n")
        if bars:
            # the three bars from the centre toward the towers, measured with a caliper
            centre = printed(s, star()[0])
            for angle in BASE_DEG:
                a = np.radians(angle)
                tip = np.array([75.0 * np.cos(a), 75.0 * np.sin(a), 0.2])
                length = np.linalg.norm(printed(s, tip)[:2] - centre[:2]) + rng.normal(0.0, 0.01)
                f.write(f"distance,0,0,0.2,{tip[0]:.6f},{tip[1]:.6f},0.2,,,{length:.5f},0.01\n")
        if heights:
            for c in probe_points():
                z = printed(s, c)[2] + rng.normal(0.0, sigma / 2)
                f.write(f"height,{c[0]:.4f},{c[1]:.4f},{c[2]:.4f},,,,,,{z:.5f},{sigma / 2}\n")


def check(settings):
    s = parse_settings(settings)
    cmd = np.array([c[:2] for c in star()])
    got = np.array([printed(s, c)[:2] for c in star()])
    # best rigid fit of the printed star onto the commanded one (Kabsch in the plane)
    a, b = cmd - cmd.mean(axis=0), got - got.mean(axis=0)
    u, _, vt = np.linalg.svd(b.T @ a)
    r = (u @ vt).T
    if np.linalg.det(r) < 0:
        u[:, -1] *= -1
        r = (u @ vt).T
    plan = np.abs(np.linalg.norm(b @ r.T - a, axis=1)).max()
    bars = max(abs(np.linalg.norm(got[i] - got[0]) - np.linalg.norm(cmd[i] - cmd[0])) for i in range(1, len(cmd)))
    height = max(abs(printed(s, c)[2] - c[2]) for c in probe_points())
    print(f"plan {plan:.6f}")
    print(f"bars {bars:.6f}")
    print(f"height {height:.6f}")


def main():
    if sys.argv[1] == "print":
        print_star(sys.argv[2], sys.argv[3], float(sys.argv[4]), int(sys.argv[5]), "--heights" in sys.argv, "--bars" in sys.argv)
    elif sys.argv[1] == "check":
        check(sys.argv[2])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
