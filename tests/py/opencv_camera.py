"""The OpenCV camera the independent photo generators share (router_photo.py, delta_photo.py):
the rays of a band of pixel rows — each pixel area-sampled S x S, rays from
cv2.undistortPoints refined by fixed-point iterations of the Brown-Conrady model until
cv2.projectPoints maps them back onto the pixels to 1e-6 px (checked on a sample) — and the
camera written as ROS camera_info YAML.
"""
import cv2
import numpy as np


def rays(K, dist, width, s, v0, v1):
    """Normalised rays (x, y, 1) of rows v0..v1, row-major, S x S samples per pixel."""
    offs = (np.arange(s) + 0.5) / s - 0.5
    us = (np.arange(width)[:, None] + offs[None, :]).reshape(-1)
    vs = (np.arange(v0, v1)[:, None] + offs[None, :]).reshape(-1)
    uu, vv = np.meshgrid(us, vs)
    px = np.stack([uu.ravel(), vv.ravel()], axis=1)
    n = cv2.undistortPoints(px.reshape(-1, 1, 2), K, dist).reshape(-1, 2)
    k1, k2, p1, p2, k3 = dist
    xd, yd = (px[:, 0] - K[0, 2]) / K[0, 0], (px[:, 1] - K[1, 2]) / K[1, 1]
    x, y = n[:, 0].copy(), n[:, 1].copy()
    for _ in range(30):
        r2 = x * x + y * y
        radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2**3
        x = (xd - (2 * p1 * x * y + p2 * (r2 + 2 * x * x))) / radial
        y = (yd - (p1 * (r2 + 2 * y * y) + 2 * p2 * x * y)) / radial
    idx = np.linspace(0, len(x) - 1, 500).astype(np.int64)
    back, _ = cv2.projectPoints(np.stack([x[idx], y[idx], np.ones(len(idx))], axis=1), np.zeros(3), np.zeros(3), K, dist)
    assert np.abs(back.reshape(-1, 2) - px[idx]).max() < 1e-6, "undistortion not converged"
    return np.stack([x, y, np.ones_like(x)], axis=1)


def write_camera_info(path, width, height, K, dist):
    m = lambda a: ", ".join(repr(float(v)) for v in a)
    with open(path, "w") as f:
        f.write(f"image_width: {width}\nimage_height: {height}\ncamera_name: opencv_truth\n")
        f.write(f"camera_matrix:\n  rows: 3\n  cols: 3\n  data: [{m(K.ravel())}]\n")
        f.write(f"distortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [{m(dist)}]\n")
        f.write("rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n")
        P = np.hstack([K, np.zeros((3, 1))])
        f.write(f"projection_matrix:\n  rows: 3\n  cols: 4\n  data: [{m(P.ravel())}]\n")
