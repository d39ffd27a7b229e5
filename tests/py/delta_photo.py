"""Photos of the calibration star a Marlin delta printed, made without metrocell: the printer
of delta_print.py (its homing, DELTA_IK and Newton on the rods) prints each dot of DOTS.csv
(commanded x, y, top z) where its physical geometry puts the nozzle — the top of a dot stands at
the nozzle's true height there, so the printer's z error changes the parallax a camera sees —
and the three ArUco tiles (cv2.aruco DICT_4X4_50, ids 1, 2, 3, 14 mm, 0.6 mm tall, 62 mm from
the centre, 15 deg counter-clockwise of the arms toward towers A, B, C, upright, a white quiet
zone one cell wide); a paper
checkerboard card (9 x 6 inner corners, 10 mm squares, a 5 mm white margin) lies on the bed
beside the star. An OpenCV camera (pinhole + Brown-Conrady; rays from cv2.undistortPoints,
refined against cv2.projectPoints) looks down from 330 mm, image top toward the machine's back;
lit from above, so dot tops and white cells are bright and the dots' walls stay as dark as the
bed; 3 x 3 area sampling, blur, noise. Rendered in bands of rows.

usage: delta_photo.py SETTINGS.gcode DOTS.csv OUT_DIR N_PHOTOS SEED
writes OUT_DIR/camera_info.yaml (the true camera) and OUT_DIR/photo_K.png
"""
import csv
import os
import sys

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import delta_print  # noqa: E402
import opencv_camera  # noqa: E402

W, HT = 2400, 1800
K = np.array([[2600.0, 0, 1199.5], [0, 2600.0, 899.5], [0, 0, 1]])
DIST = np.array([-0.08, 0.03, 0.0002, -0.0002, 0.0])
S = 3
CARD_X0, CARD_Y0, SQ, COLS, ROWS = 88.0, -35.0, 10.0, 9, 6  # card's corner (mm), inner corners


def rays(v0, v1):
    return opencv_camera.rays(K, DIST, W, S, v0, v1)


def on_plane(d, R, t, z):
    """Bed-frame (mm) points where camera rays d meet the plane z (mm)."""
    rt = R.T
    origin = -rt @ t
    dirs = d @ rt.T
    lam = (z - origin[2]) / dirs[:, 2]
    return origin[None, :] + lam[:, None] * dirs


def tile_bits(marker_id):
    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    marker = cv2.aruco.generateImageMarker(d, marker_id, 6, borderBits=1) > 127  # True = white
    return np.pad(marker, 1, constant_values=True)  # the white quiet zone: 8 x 8 cells


def scene(settings, dots_csv):
    s = delta_print.parse_settings(settings)
    dots = []
    for row in csv.DictReader(open(dots_csv)):
        c = np.array([float(row["x_mm"]), float(row["y_mm"]), float(row["z_mm"])])
        dots.append(delta_print.printed(s, c))  # the nozzle's true place at the dot's top
    tiles = []
    for t, deg in enumerate(delta_print.BASE_DEG):
        a = np.radians(deg + 15.0)
        centre = delta_print.printed(s, np.array([62.0 * np.cos(a), 62.0 * np.sin(a), 0.6]))
        tiles.append((centre, tile_bits(t + 1)))
    return np.array(dots), tiles


def shade(d, R, t, dots, tiles):
    bed = on_plane(d, R, t, 0.0)
    x, y = bed[:, 0], bed[:, 1]
    value = np.full(len(x), 45.0)  # the bed: dark
    on_card = (x > CARD_X0 - 5) & (x < CARD_X0 + (COLS + 1) * SQ + 5) & (y > CARD_Y0 - 5) & (y < CARD_Y0 + (ROWS + 1) * SQ + 5)
    value = np.where(on_card, 225.0, value)
    i = np.floor((x - CARD_X0) / SQ)
    j = np.floor((y - CARD_Y0) / SQ)
    squares = (i >= 0) & (i <= COLS) & (j >= 0) & (j <= ROWS)
    value = np.where(squares & ((i + j) % 2 == 0), 25.0, value)
    for centre, bits in tiles:
        p = on_plane(d, R, t, centre[2])
        u = (p[:, 0] - (centre[0] - 7.0)) / (14.0 / 8)
        v = ((centre[1] + 7.0) - p[:, 1]) / (14.0 / 8)  # rows down from the tile's top edge (+Y)
        inside = (u >= 0) & (u < 8) & (v >= 0) & (v < 8)
        cells = bits[np.clip(v.astype(int), 0, 7), np.clip(u.astype(int), 0, 7)]
        value = np.where(inside, np.where(cells, 230.0, 30.0), value)
    for c in dots:
        p = on_plane(d, R, t, c[2])
        value = np.where((p[:, 0] - c[0]) ** 2 + (p[:, 1] - c[1]) ** 2 < 1.5**2, 235.0, value)
    return value


def photo(R, t, dots, tiles, seed):
    img = np.zeros((HT, W))
    band = 40
    # where each dot falls in the image, so a band of rows only draws the dots it can see
    rvec, _ = cv2.Rodrigues(R)
    at, _ = cv2.projectPoints(dots.reshape(-1, 1, 3), rvec, t, K, DIST)
    rows = at.reshape(-1, 2)[:, 1]
    for v0 in range(0, HT, band):
        v1 = min(HT, v0 + band)
        near = dots[(rows > v0 - 40) & (rows < v1 + 40)]
        val = shade(rays(v0, v1), R, t, near, tiles)
        img[v0:v1] = val.reshape(v1 - v0, S, W, S).mean(axis=(1, 3))
    img = cv2.GaussianBlur(img, (0, 0), 0.7)
    img += np.random.default_rng(seed).normal(0.0, 2.0, img.shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def main():
    settings, dots_csv, out, n, seed = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
    os.makedirs(out, exist_ok=True)
    dots, tiles = scene(settings, dots_csv)
    rng = np.random.default_rng(seed)
    for k in range(n):
        # looking down (camera x = bed x, camera y = bed -y), a little tilted, from ~330 mm
        tilt = cv2.Rodrigues(rng.normal(0.0, 0.03, 3))[0]
        R = tilt @ np.diag([1.0, -1.0, -1.0])
        centre = np.array([55.0 + rng.normal(0, 3), rng.normal(0, 3), 330.0])
        t = -R @ centre
        cv2.imwrite(os.path.join(out, f"photo_{k}.png"), photo(R, t, dots, tiles, seed * 100 + k))
    opencv_camera.write_camera_info(os.path.join(out, "camera_info.yaml"), W, HT, K, DIST)


if __name__ == "__main__":
    main()
