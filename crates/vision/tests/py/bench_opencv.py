"""Times OpenCV's ArUco detector on PNG frames, one detection per request, so that the Rust
benchmark can interleave its own runs with OpenCV's (a busy machine then slows both alike).

  bench_opencv.py DICT REFINE IMG...
  stdin, one request a line:  THREADS INDEX   (cv2.setNumThreads(THREADS); detect on IMG[INDEX])
  stdout, one reply a line:   SECONDS FOUND   (detectMarkers wall time; markers found)
"""
import sys
import time

import cv2

A = cv2.aruco


def main(name, refine, *paths):
    params = A.DetectorParameters()
    params.cornerRefinementMethod = {"none": A.CORNER_REFINE_NONE, "subpix": A.CORNER_REFINE_SUBPIX}[refine]
    det = A.ArucoDetector(A.getPredefinedDictionary(getattr(A, name)), params)
    imgs = [cv2.imread(p, cv2.IMREAD_GRAYSCALE) for p in paths]
    for line in sys.stdin:
        threads, k = (int(v) for v in line.split())
        cv2.setNumThreads(threads)
        t0 = time.perf_counter()
        _, ids, _ = det.detectMarkers(imgs[k])
        dt = time.perf_counter() - t0
        print(f"{dt:.9f} {0 if ids is None else len(ids)}", flush=True)


if __name__ == "__main__":
    main(*sys.argv[1:])
