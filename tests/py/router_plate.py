"""A drilled calibration plate's hole errors, written from seed 000's eq. 7 and Table 2 (B72)
directly, not by metrocell: a 6 x 6 grid (pitch 25 mm, centres 12.5 ... 137.5 mm), X3 = 1,
Gaussian measurement noise of the stated sigma per axis.

usage: router_plate.py OUT.csv SIGMA_MM SEED
"""
import sys

import numpy as np

A, B, C, D, E, F, G, H, I = 1.01e-5, 5.20e-3, -7.10e-3, 4.85e-3, 1.11e-2, 1.03e-2, -1.12e-5, -2.01e-5, -1.55e-5


def main():
    out, sigma, seed = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
    rng = np.random.default_rng(seed)
    centres = 12.5 + 25.0 * np.arange(6)
    with open(out, "w") as f:
        f.write("hole,x_mm,y_mm,ex_mm,ey_mm,sigma_x_mm,sigma_y_mm\n")
        k = 0
        for x1 in centres:
            for x2 in centres:
                ex = A * x2**2 + B * x2 + C * x1 + D * 1.0
                ey = E * x1 + F * x2 + G * 1.0 + H * x1 * x2 + I * x1**2
                nx, ny = (rng.normal(0.0, sigma, 2) if sigma > 0 else (0.0, 0.0))
                k += 1
                f.write(f"{k},{x1:.3f},{x2:.3f},{ex + nx:.6f},{ey + ny:.6f},{max(sigma, 1e-4):.6f},{max(sigma, 1e-4):.6f}\n")


if __name__ == "__main__":
    main()
