"""A calibrated hole plate probed on a machine, written from geometry alone (seed 001 part 2
§1.7; no metrocell code): the machine's axes are direction vectors — the Y motion leaning so
that the angle between +X and +Y is 90° + xWy (the thesis's plate found 0.20448 mrad) — with a
sine pitch error and a linear scale on X, a bow on each axis, the X table yawing as it moves and
pitching over the probe's height. The plate (460 × 460 mm aluminium, α 24e-6 /K, rings of
12.5 mm radius at 50 mm pitch; the peripheral rings of a 9 × 9 grid) lies 0.3° askew, clamped
at (200, 250) mm, at 21.3 °C. Each ring is probed at +X, −X, +Y, −Y: the machine reports its
commanded position at contact, with 0.5 µm of noise.

    python hole_plate.py OUT_DIR [XWY_MRAD] [SEED]

writes OUT_DIR/nominal.csv (hole,x_mm,y_mm at 20 °C) and OUT_DIR/z50.csv, OUT_DIR/z250.csv
(hole,x_mm,y_mm: four probe points per hole, the plate probed at 50 and 250 mm height).
"""
import math
import random
import sys
from pathlib import Path

out = Path(sys.argv[1])
xwy = float(sys.argv[2]) * 1e-3 if len(sys.argv) > 2 else 0.20448e-3
rng = random.Random(int(sys.argv[3]) if len(sys.argv) > 3 else 1)
out.mkdir(parents=True, exist_ok=True)

def machine(x, y, z):
    """Where the probe is when commanded to (x, y) at height z, from (0, 0, z), m."""
    pitch = 4e-6 * math.sin(2 * math.pi * x / 0.35) + 12e-6 * x / 0.4
    y_pos = -9e-6 * (y / 0.4) ** 2 + 6e-6 * y / 0.4
    x_bow = 5e-6 * (x / 0.4) * (x / 0.4 - 1)
    y_bow = -4e-6 * (y / 0.4) * (y / 0.4 - 1)
    yaw = 15e-6 * x / 0.4
    x_pitch = 20e-6 * (x / 0.4 - 0.5)
    ydx, ydy = -math.sin(xwy), math.cos(xwy)
    return (x + ydx * y + pitch + y_bow - y * yaw + z * x_pitch,
            ydy * y + y_pos + x_bow)

holes = []
for i in range(9):
    for j in range(9):
        if i in (0, 8) or j in (0, 8):
            holes.append((f"H{i}{j}", 0.03 + 0.05 * i, 0.03 + 0.05 * j))
with open(out / "nominal.csv", "w") as f:
    f.write("hole,x_mm,y_mm\n")
    for h, x, y in holes:
        f.write(f"{h},{x * 1e3:.4f},{y * 1e3:.4f}\n")

theta, ox, oy, cx, cy, t, alpha, r = math.radians(0.3), 0.412, 0.137, 0.2, 0.25, 21.3, 24e-6, 0.0125
for z, name in ((0.05, "z50.csv"), (0.25, "z250.csv")):
    with open(out / name, "w") as f:
        f.write("hole,x_mm,y_mm\n")
        for h, x, y in holes:
            ex, ey = cx + (x - cx) * (1 + alpha * (t - 20)), cy + (y - cy) * (1 + alpha * (t - 20))
            px = ox + math.cos(theta) * ex - math.sin(theta) * ey
            py = oy + math.sin(theta) * ex + math.cos(theta) * ey
            for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                wx, wy = px + dx * r, py + dy * r
                mx, my = machine(wx, wy, z)
                # commanded at contact: the wall less the machine's error there
                rx = wx - (mx - wx) + rng.gauss(0, 0.5e-6)
                ry = wy - (my - wy) + rng.gauss(0, 0.5e-6)
                f.write(f"{h},{rx * 1e3:.5f},{ry * 1e3:.5f}\n")
