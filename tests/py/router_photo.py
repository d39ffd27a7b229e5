"""Photos of a drilled seed 000 plate, made without metrocell: a 6 x 6 checkerboard of 25 mm
squares (front-left square black) laid on a router's table with its front-left corner at the
machine origin, one hole drilled per square where a router with seed 000's B72 error field
(eq. 7, X3 = 1, evaluated in numpy) puts it, a backing of the inverse colours under it (a hole
through a white square shows black); photographed from above, the machine's back at the top of
the image, by an OpenCV camera (pinhole + Brown-Conrady distortion: rays from
cv2.undistortPoints, refined until cv2.projectPoints maps them back to 1e-6 px), area-sampled
3 x 3 per pixel, blurred and noised. Rendered in bands of rows so memory stays small.

usage: router_photo.py OUT_DIR N_PHOTOS SEED [HOLE_MM]
writes OUT_DIR/camera_info.yaml (ROS camera_info, the true camera), OUT_DIR/photo_K.png, and
OUT_DIR/truth.csv (hole,x_mm,y_mm,ex_mm,ey_mm: where each hole was drilled, machine mm)
"""
import os
import sys

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import opencv_camera  # noqa: E402

A, B, C, D, E, F, G, H, I = 1.01e-5, 5.20e-3, -7.10e-3, 4.85e-3, 1.11e-2, 1.03e-2, -1.12e-5, -2.01e-5, -1.55e-5
N, SQ = 6, 25.0  # squares, mm
W, HT = 2000, 1800  # px
K = np.array([[3000.0, 0, 999.5], [0, 3000.0, 899.5], [0, 0, 1]])
DIST = np.array([-0.12, 0.05, 0.0004, -0.0003, 0.0])
S = 3  # supersampling


def drilled():
    """Machine (X, Y) of each hole, row-major from the front-left, with its error."""
    out = []
    for r in range(N):
        for c in range(N):
            x1, x2 = (c + 0.5) * SQ, (r + 0.5) * SQ
            ex = A * x2**2 + B * x2 + C * x1 + D
            ey = E * x1 + F * x2 + G + H * x1 * x2 + I * x1**2
            out.append((x1, x2, ex, ey))
    return out


def rays(v0, v1):
    return opencv_camera.rays(K, DIST, W, S, v0, v1)


def shade(bx, by, holes, hole_mm):
    """Grey level at board-frame points (mm; x right, y down the image, origin at the board's
    back-left corner as seen from above)."""
    col = np.floor(bx / SQ)
    row_img = np.floor(by / SQ)
    inside = (col >= 0) & (col < N) & (row_img >= 0) & (row_img < N)
    machine_row = N - 1 - row_img
    black = ((col + machine_row) % 2 == 0)
    value = np.where(black, 30.0, 220.0)
    for (x1, x2, ex, ey) in holes:
        hx, hy = x1 + ex, N * SQ - (x2 + ey)
        in_hole = (bx - hx) ** 2 + (by - hy) ** 2 < (hole_mm / 2) ** 2
        value = np.where(in_hole, 250.0 - value, value)
    return np.where(inside, value, 140.0)


def photo(rvec, tvec, holes, hole_mm, seed):
    R, _ = cv2.Rodrigues(rvec)
    rt = R.T
    img = np.zeros((HT, W))
    band = 60
    for v0 in range(0, HT, band):
        v1 = min(HT, v0 + band)
        d = rays(v0, v1)
        lam = (rt @ tvec)[2] / (d @ rt[2])
        X = (lam[:, None] * d) @ rt.T - rt @ tvec
        val = shade(X[:, 0] * 1e3, X[:, 1] * 1e3, holes, hole_mm)
        img[v0:v1] = val.reshape(v1 - v0, S, W, S).mean(axis=(1, 3))
    img = cv2.GaussianBlur(img, (0, 0), 0.7)
    img += np.random.default_rng(seed).normal(0.0, 2.0, img.shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def main():
    out, n, seed = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    hole_mm = float(sys.argv[4]) if len(sys.argv) > 4 else 1.5
    os.makedirs(out, exist_ok=True)
    holes = drilled()
    with open(os.path.join(out, "truth.csv"), "w") as f:
        f.write("hole,x_mm,y_mm,ex_mm,ey_mm\n")
        for k, (x1, x2, ex, ey) in enumerate(holes):
            f.write(f"{k + 1},{x1},{x2},{ex:.6f},{ey:.6f}\n")
    rng = np.random.default_rng(seed)
    for k in range(n):
        # the board's centre 0.3 m below the camera, turned and tilted a little
        tilt = rng.normal(0.0, 0.05, 2)
        rvec = np.array([tilt[0], tilt[1], rng.normal(0.0, 0.03)])
        R, _ = cv2.Rodrigues(rvec)
        centre = np.array([N * SQ / 2e3, N * SQ / 2e3, 0.0])
        tvec = np.array([rng.normal(0.0, 0.005), rng.normal(0.0, 0.005), 0.30]) - R @ centre
        cv2.imwrite(os.path.join(out, f"photo_{k}.png"), photo(rvec, tvec, holes, hole_mm, seed * 100 + k))
    opencv_camera.write_camera_info(os.path.join(out, "camera_info.yaml"), W, HT, K, DIST)


if __name__ == "__main__":
    main()
