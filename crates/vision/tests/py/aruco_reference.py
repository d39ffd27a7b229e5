"""OpenCV reference for the metrocell-vision ArUco tests. Prints JSON on stdout.

Subcommands:
  dict NAME                          -> {"marker_size", "max_correction_bits", "bytes": [[[b0r0..b0r3], ...], ...]}
  markers NAME SIDE BORDER OUTDIR ID...  -> writes OUTDIR/marker_<id>.png with generateImageMarker
  detect NAME REFINE IMG...           -> per image: list of {"id", "corners": [[x,y]*4]}
                                         REFINE in {none, subpix, contour}
  pose NAME SIDE fx fy cx cy k1 k2 p1 p2 k3 IMG...
                                      -> per image: list of {"id", "rvec", "tvec"} from detectMarkers
                                         (CORNER_REFINE_SUBPIX) + solvePnP(SOLVEPNP_IPPE_SQUARE)
"""
import json
import sys

import cv2
import numpy as np

A = cv2.aruco


def dictionary(name):
    return A.getPredefinedDictionary(getattr(A, name))


def cmd_dict(name):
    d = dictionary(name)
    print(json.dumps({
        "marker_size": int(d.markerSize),
        "max_correction_bits": int(d.maxCorrectionBits),
        "bytes": d.bytesList.astype(int).tolist(),
    }))


def cmd_markers(name, side, border, outdir, *ids):
    d = dictionary(name)
    for i in ids:
        img = A.generateImageMarker(d, int(i), int(side), borderBits=int(border))
        cv2.imwrite(f"{outdir}/marker_{i}.png", img)
    print(json.dumps({"written": len(ids)}))


def cmd_detect(name, refine, *paths):
    params = A.DetectorParameters()
    params.cornerRefinementMethod = {
        "none": A.CORNER_REFINE_NONE,
        "subpix": A.CORNER_REFINE_SUBPIX,
        "contour": A.CORNER_REFINE_CONTOUR,
    }[refine]
    det = A.ArucoDetector(dictionary(name), params)
    out = []
    for p in paths:
        img = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
        if img is None:
            raise SystemExit(f"cannot read {p}")
        corners, ids, _ = det.detectMarkers(img)
        found = []
        if ids is not None:
            for c, i in zip(corners, ids.flatten()):
                found.append({"id": int(i), "corners": c.reshape(4, 2).astype(float).tolist()})
        out.append(found)
    print(json.dumps(out))


def cmd_pose(name, side, fx, fy, cx, cy, k1, k2, p1, p2, k3, *paths):
    s = float(side) / 2
    obj = np.array([[-s, s, 0], [s, s, 0], [s, -s, 0], [-s, -s, 0]], dtype=np.float64)
    K = np.array([[float(fx), 0, float(cx)], [0, float(fy), float(cy)], [0, 0, 1]])
    dist = np.array([float(k1), float(k2), float(p1), float(p2), float(k3)])
    params = A.DetectorParameters()
    params.cornerRefinementMethod = A.CORNER_REFINE_SUBPIX
    det = A.ArucoDetector(dictionary(name), params)
    out = []
    for p in paths:
        img = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
        corners, ids, _ = det.detectMarkers(img)
        found = []
        if ids is not None:
            for c, i in zip(corners, ids.flatten()):
                ok, rvec, tvec = cv2.solvePnP(obj, c.reshape(4, 2).astype(np.float64), K, dist, flags=cv2.SOLVEPNP_IPPE_SQUARE)
                if ok:
                    found.append({"id": int(i), "rvec": rvec.flatten().tolist(), "tvec": tvec.flatten().tolist()})
        out.append(found)
    print(json.dumps(out))


if __name__ == "__main__":
    cmd = sys.argv[1]
    {"dict": cmd_dict, "markers": cmd_markers, "detect": cmd_detect, "pose": cmd_pose}[cmd](*sys.argv[2:])
