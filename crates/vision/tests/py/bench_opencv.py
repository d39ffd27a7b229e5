"""Times OpenCV's ArUco detector on PNG frames (same frames the Rust benchmark times).

  bench_opencv.py DICT REFINE THREADS REPEATS IMG...  -> JSON list of {"median_s", "found"} per image
"""
import json
import sys
import time

import cv2

A = cv2.aruco


def main(name, refine, threads, repeats, *paths):
    cv2.setNumThreads(int(threads))
    params = A.DetectorParameters()
    params.cornerRefinementMethod = {"none": A.CORNER_REFINE_NONE, "subpix": A.CORNER_REFINE_SUBPIX}[refine]
    det = A.ArucoDetector(A.getPredefinedDictionary(getattr(A, name)), params)
    out = []
    for p in paths:
        img = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
        det.detectMarkers(img)  # warm-up
        times = []
        for _ in range(int(repeats)):
            t0 = time.perf_counter()
            corners, ids, _ = det.detectMarkers(img)
            times.append(time.perf_counter() - t0)
        times.sort()
        out.append({"median_s": times[len(times) // 2], "found": 0 if ids is None else int(len(ids))})
    print(json.dumps(out))


if __name__ == "__main__":
    main(*sys.argv[1:])
