"""A calibrated sphere probed with the head turned every 15° (seed 001 part 2 §1.6), written
from geometry alone (no metrocell code): the stylus tip sits `ecc` mm off the spindle axis
(turning with the head), and the probe's pretravel varies with the direction it is deflected
in, p(φ) = p0 + lobe·cos(3φ) in the probe's own frame (kinematic three-point seating). The sphere
(Ø 25 mm) is probed at +X, −X, +Y, −Y around its equator and once on top; the centre is
the midpoint of each pair (x, y) and the top point less the radius (z). Noise 2 µm per point.

    python probe_tip.py OUT.csv ECC_MM LOBE_UM [SEED]

writes angle_deg,x_mm,y_mm,z_mm for 24 head angles.
"""
import math
import random
import sys

out, ecc, lobe = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]) * 1e-3
rng = random.Random(int(sys.argv[4]) if len(sys.argv) > 4 else 1)
centre = (250.0, 180.0, -40.0)
radius, p0, noise = 12.5, 0.010, 0.002
with open(out, "w") as f:
    f.write("angle_deg,x_mm,y_mm,z_mm\n")
    for k in range(24):
        theta = math.radians(15 * k)
        tip = (ecc * math.cos(theta + 0.4), ecc * math.sin(theta + 0.4))

        def touch(d):
            # the probe moves along d (unit, in XY) toward the sphere; its ball touches where
            # the spindle is at c − r·d − tip; the probe triggers after its pretravel along d,
            # deflected at φ = dir − θ in its own frame: the controller reports that position
            phi = math.atan2(d[1], d[0]) - theta
            pre = p0 + lobe * math.cos(3 * phi)
            return [centre[i] - radius * d[i] - tip[i] + pre * d[i] + rng.gauss(0, noise) for i in range(2)]

        px, mx = touch((1, 0)), touch((-1, 0))
        py, my = touch((0, 1)), touch((0, -1))
        top = centre[2] + radius - p0 + rng.gauss(0, noise)
        x = (px[0] + mx[0]) / 2
        y = (py[1] + my[1]) / 2
        f.write(f"{15 * k},{x:.5f},{y:.5f},{top - radius:.5f}\n")
