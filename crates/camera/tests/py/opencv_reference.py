#!/usr/bin/env python3
"""OpenCV reference for metrocell-camera tests.

Reads one JSON request on stdin, runs the named OpenCV operation on exactly the given inputs and
writes a JSON answer on stdout. Operations: project, undistort_points, undistort_map, calibrate,
solvepnp_ippe. Requires numpy and opencv-contrib-python-headless.
"""
import json
import sys

import cv2
import numpy as np


def k_matrix(c):
    return np.array([[c["fx"], 0.0, c["cx"]], [0.0, c["fy"], c["cy"]], [0.0, 0.0, 1.0]])


def dist(c):
    return np.array(c["coeffs"], dtype=np.float64)


def is_fisheye(c):
    return c["model"] == "fisheye"


def op_project(req):
    c = req["camera"]
    obj = np.array(req["object_points"], dtype=np.float64).reshape(-1, 1, 3)
    rvec = np.array(req["rvec"], dtype=np.float64)
    tvec = np.array(req["tvec"], dtype=np.float64)
    if is_fisheye(c):
        pts, _ = cv2.fisheye.projectPoints(obj, rvec.reshape(1, 1, 3), tvec.reshape(1, 1, 3), k_matrix(c), dist(c))
    else:
        pts, _ = cv2.projectPoints(obj, rvec, tvec, k_matrix(c), dist(c))
    return {"pixels": pts.reshape(-1, 2).tolist()}


def criteria_of(req):
    cr = req.get("criteria")
    if cr is None:
        return None
    t = cv2.TERM_CRITERIA_COUNT
    eps = 0.0
    if cr.get("epsilon") is not None:
        t |= cv2.TERM_CRITERIA_EPS
        eps = cr["epsilon"]
    return (t, int(cr["max_iterations"]), float(eps))


def op_undistort_points(req):
    c = req["camera"]
    px = np.array(req["pixels"], dtype=np.float64).reshape(-1, 1, 2)
    crit = criteria_of(req)
    P = np.array(req["new_camera"], dtype=np.float64) if req.get("new_camera") is not None else None
    R = np.array(req["rectification"], dtype=np.float64) if req.get("rectification") is not None else None
    if is_fisheye(c):
        kwargs = {}
        if crit is not None:
            kwargs["criteria"] = crit
        out = cv2.fisheye.undistortPoints(px, k_matrix(c), dist(c), R=R, P=P, **kwargs)
    elif crit is not None:
        out = cv2.undistortPoints(px, k_matrix(c), dist(c), R=R, P=P, criteria=crit)
    else:
        out = cv2.undistortPoints(px, k_matrix(c), dist(c), R=R, P=P)
    return {"points": out.reshape(-1, 2).tolist()}


def op_undistort_map(req):
    c = req["camera"]
    size = tuple(req["size"])
    P = np.array(req["new_camera"], dtype=np.float64) if req.get("new_camera") is not None else k_matrix(c)
    R = np.array(req["rectification"], dtype=np.float64) if req.get("rectification") is not None else np.eye(3)
    if is_fisheye(c):
        mx, my = cv2.fisheye.initUndistortRectifyMap(k_matrix(c), dist(c), R, P, size, cv2.CV_32FC1)
    else:
        mx, my = cv2.initUndistortRectifyMap(k_matrix(c), dist(c), R, P, size, cv2.CV_32FC1)
    return {"map_x": mx.astype(np.float64).ravel().tolist(), "map_y": my.astype(np.float64).ravel().tolist()}


def op_calibrate(req):
    views = req["views"]
    size = tuple(req["image_size"])
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 500, 1e-16)
    if req["model"] == "fisheye":
        # cv::fisheye::calibrate wants 1×N point arrays (N×1 fails inside arithm_op).
        obj = [np.array(v["object_points"], dtype=np.float64).reshape(1, -1, 3) for v in views]
        img = [np.array(v["image_points"], dtype=np.float64).reshape(1, -1, 2) for v in views]
        flags = getattr(cv2, "CALIB_RECOMPUTE_EXTRINSIC", None) or cv2.fisheye.CALIB_RECOMPUTE_EXTRINSIC
        flags |= getattr(cv2, "CALIB_FIX_SKEW", None) or cv2.fisheye.CALIB_FIX_SKEW
        rms, K, D, rvecs, tvecs = cv2.fisheye.calibrate(obj, img, size, np.eye(3), np.zeros((4, 1)), flags=flags, criteria=crit)
        return {"rms": rms, "fx": K[0, 0], "fy": K[1, 1], "cx": K[0, 2], "cy": K[1, 2],
                "coeffs": np.asarray(D).ravel().tolist()}
    obj = [np.array(v["object_points"], dtype=np.float32).reshape(-1, 3) for v in views]
    img = [np.array(v["image_points"], dtype=np.float32).reshape(-1, 2) for v in views]
    flags = 0
    for name in req.get("flags", []):
        flags |= getattr(cv2, name)
    # Identity K: aspect ratio 1 for CALIB_FIX_ASPECT_RATIO (ignored otherwise without a guess).
    rms, K, D, rvecs, tvecs, std_i, std_e, per_view = cv2.calibrateCameraExtended(
        obj, img, size, np.eye(3), np.zeros(5), flags=flags, criteria=crit)
    std_i = np.asarray(std_i).ravel()
    return {"rms": rms, "fx": K[0, 0], "fy": K[1, 1], "cx": K[0, 2], "cy": K[1, 2],
            "coeffs": np.asarray(D).ravel()[:5].tolist(), "std_intrinsics": std_i[:9].tolist(),
            "per_view_rms": np.asarray(per_view).ravel().tolist()}


def op_solvepnp_ippe(req):
    c = req["camera"]
    obj = np.array(req["object_points"], dtype=np.float64).reshape(-1, 1, 3)
    img = np.array(req["image_points"], dtype=np.float64).reshape(-1, 1, 2)
    ok, rvec, tvec = cv2.solvePnP(obj, img, k_matrix(c), dist(c), flags=cv2.SOLVEPNP_IPPE)
    if not ok:
        raise RuntimeError("solvePnP(IPPE) failed")
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
    r2, t2 = cv2.solvePnPRefineLM(obj, img, k_matrix(c), dist(c), rvec.copy(), tvec.copy(), criteria=crit)
    return {"rvec": rvec.ravel().tolist(), "tvec": tvec.ravel().tolist(),
            "rvec_lm": r2.ravel().tolist(), "tvec_lm": t2.ravel().tolist()}


def op_solvepnp_sqpnp(req):
    """General (non-planar) PnP: SQPnP then Levenberg-Marquardt refinement."""
    c = req["camera"]
    obj = np.array(req["object_points"], dtype=np.float64).reshape(-1, 1, 3)
    img = np.array(req["image_points"], dtype=np.float64).reshape(-1, 1, 2)
    ok, rvec, tvec = cv2.solvePnP(obj, img, k_matrix(c), dist(c), flags=cv2.SOLVEPNP_SQPNP)
    if not ok:
        raise RuntimeError("solvePnP(SQPNP) failed")
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
    r2, t2 = cv2.solvePnPRefineLM(obj, img, k_matrix(c), dist(c), rvec.copy(), tvec.copy(), criteria=crit)
    return {"rvec_lm": r2.ravel().tolist(), "tvec_lm": t2.ravel().tolist()}


OPS = {"solvepnp_sqpnp": op_solvepnp_sqpnp, "project": op_project, "undistort_points": op_undistort_points, "undistort_map": op_undistort_map,
       "calibrate": op_calibrate, "solvepnp_ippe": op_solvepnp_ippe}


def main():
    req = json.load(sys.stdin)
    out = OPS[req["op"]](req)
    out["opencv_version"] = cv2.__version__
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
