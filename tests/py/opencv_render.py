"""Test images made without metrocell's renderer: a planar target seen by an OpenCV camera
(pinhole + Brown-Conrady distortion), rendered by inverse warping (OpenCV's `undistortPoints`, refined and
checked against its `projectPoints`), area-sampled by supersampling, then blurred and noised.

Each output pixel (u, v) (OpenCV convention: the top-left pixel's centre is (0, 0)) averages
S x S sub-pixel samples at u + (i + 0.5)/S - 0.5; each sample's ray (undistortPoints) meets the
target plane z = 0 of the pose (rvec, tvec), and the target's pattern is evaluated there exactly:
- checkerboard: COLS x ROWS inner corners, square side SQ (m), corner (0, 0) at the origin, the
  first square (-SQ..0, -SQ..0) black, a white margin of one square around the board;
- aruco: one OpenCV-generated marker (cv2.aruco.generateImageMarker) of side SIDE (m), its
  top-left corner at the origin, x right and y down along the marker, a white margin.
Ground truth: the target's corners projected with cv2.projectPoints.

Usage: opencv_render.py REQUEST_JSON   (prints a JSON answer; see main())
"""

import json
import sys

import cv2
import numpy as np


def camera_rays(camera, s):
    """K, distortion and the ray (x, y, 1) of every sub-pixel sample, row-major."""
    w, h = camera["width"], camera["height"]
    K = np.array([[camera["fx"], 0, camera["cx"]], [0, camera["fy"], camera["cy"]], [0, 0, 1.0]])
    dist = np.array(camera["dist"], dtype=np.float64)
    offs = (np.arange(s) + 0.5) / s - 0.5
    us = (np.arange(w)[:, None] + offs[None, :]).reshape(-1)
    vs = (np.arange(h)[:, None] + offs[None, :]).reshape(-1)
    uu, vv = np.meshgrid(us, vs)
    n = undistort(np.stack([uu.ravel(), vv.ravel()], axis=1), K, dist)
    return K, dist, np.concatenate([n, np.ones((n.shape[0], 1))], axis=1)


def render(spec, camera, pattern, s, K, dist, rays):
    w, h = camera["width"], camera["height"]
    rvec = np.array(spec["rvec"], dtype=np.float64)
    tvec = np.array(spec["tvec"], dtype=np.float64)
    R, _ = cv2.Rodrigues(rvec)
    # plane z = 0 of the target: X = R^T (lambda ray - t); solve for z = 0
    rt = R.T
    num = (rt @ tvec)[2]
    den = rays @ rt[2]
    lam = num / den
    X = (lam[:, None] * rays) @ rt.T - rt @ tvec
    value = pattern(X[:, 0], X[:, 1])
    value = value.reshape(h * s, w * s)
    img = value.reshape(h, s, w, s).mean(axis=(1, 3))
    if spec.get("blur", 0) > 0:
        img = cv2.GaussianBlur(img, (0, 0), spec["blur"])
    rng = np.random.default_rng(spec.get("seed", 0))
    img = img + rng.normal(0.0, spec.get("noise", 0.0), img.shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8), K, dist, rvec, tvec


def undistort(px, K, dist):
    """Normalised coordinates of pixels: OpenCV's undistortPoints, refined by fixed-point
    iterations of the Brown-Conrady model until OpenCV's projectPoints maps them back onto the
    pixels to 1e-6 px (checked on a sample)."""
    n = cv2.undistortPoints(px.reshape(-1, 1, 2), K, dist).reshape(-1, 2)
    k1, k2, p1, p2, k3 = dist
    xd = (px[:, 0] - K[0, 2]) / K[0, 0]
    yd = (px[:, 1] - K[1, 2]) / K[1, 1]
    x, y = n[:, 0].copy(), n[:, 1].copy()
    for _ in range(30):
        r2 = x * x + y * y
        radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 ** 3
        dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        x = (xd - dx) / radial
        y = (yd - dy) / radial
    idx = np.linspace(0, len(x) - 1, 2000).astype(np.int64)
    obj = np.stack([x[idx], y[idx], np.ones(len(idx))], axis=1)
    back, _ = cv2.projectPoints(obj, np.zeros(3), np.zeros(3), K, dist)
    err = np.abs(back.reshape(-1, 2) - px[idx]).max()
    assert err < 1e-6, f"undistortion not converged: {err} px"
    return np.stack([x, y], axis=1)


def checker_pattern(cols, rows, sq, dark=30.0, light=220.0):
    def f(x, y):
        i = np.floor(x / sq) + 1
        j = np.floor(y / sq) + 1
        inside = (i >= 0) & (i <= cols) & (j >= 0) & (j <= rows)
        black = ((i + j) % 2 == 0) & inside
        return np.where(black, dark, light)
    return f


def aruco_pattern(dict_name, marker_id, side, dark=30.0, light=220.0):
    d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dict_name))
    cells = d.markerSize + 2
    tile = cv2.aruco.generateImageMarker(d, marker_id, cells, borderBits=1)
    def f(x, y):
        i = np.floor(x / side * cells).astype(np.int64)
        j = np.floor(y / side * cells).astype(np.int64)
        inside = (i >= 0) & (i < cells) & (j >= 0) & (j < cells)
        v = tile[np.clip(j, 0, cells - 1), np.clip(i, 0, cells - 1)]
        return np.where(inside, np.where(v > 127, light, dark), light)
    return f


def main():
    req = json.loads(open(sys.argv[1]).read())
    cam = req["camera"]
    s = req.get("supersample", 4)
    K, dist, rays = camera_rays(cam, s)
    out = []
    for k, view in enumerate(req["views"]):
        if req["target"] == "checkerboard":
            cols, rows, sq = req["cols"], req["rows"], req["square"]
            pattern = checker_pattern(cols, rows, sq)
            obj = np.array([[(c % cols) * sq, (c // cols) * sq, 0.0] for c in range(cols * rows)])
        else:
            side = req["side"]
            pattern = aruco_pattern(req["dictionary"], req["id"], side)
            obj = np.array([[0, 0, 0], [side, 0, 0], [side, side, 0], [0, side, 0]], dtype=np.float64)
        img, K, dist, rvec, tvec = render(view, cam, pattern, s, K, dist, rays)
        path = f"{req['out_dir']}/view_{k:02d}.png"
        cv2.imwrite(path, img)
        truth, _ = cv2.projectPoints(obj, rvec, tvec, K, dist)
        item = {"path": path, "corners": truth.reshape(-1, 2).tolist()}
        if req["target"] == "aruco":
            # OpenCV's detector on the same file, for the comparison
            d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, req["dictionary"]))
            params = cv2.aruco.DetectorParameters()
            params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
            corners, ids, _ = cv2.aruco.ArucoDetector(d, params).detectMarkers(cv2.imread(path, cv2.IMREAD_GRAYSCALE))
            item["opencv"] = [{"id": int(i), "corners": c.reshape(-1, 2).tolist()} for c, i in zip(corners, (ids if ids is not None else np.zeros((0, 1))).ravel())]
        out.append(item)
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
