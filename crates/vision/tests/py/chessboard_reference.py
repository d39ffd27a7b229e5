"""OpenCV checkerboard reference: inner corners of a COLSxROWS (inner corners) pattern.

  chessboard COLS ROWS IMG...  -> per image {"sb": [[x,y],...] or null, "subpix": [[x,y],...] or null}
    sb:     cv2.findChessboardCornersSB (its own sub-pixel estimate)
    subpix: cv2.findChessboardCorners + cv2.cornerSubPix(win 5x5, eps 1e-4, 100 it)
"""
import json
import sys

import cv2
import numpy as np


def main(cols, rows, *paths):
    size = (int(cols), int(rows))
    out = []
    for p in paths:
        img = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
        ok, sb = cv2.findChessboardCornersSB(img, size, flags=cv2.CALIB_CB_ACCURACY)
        ok2, c = cv2.findChessboardCorners(img, size)
        sub = None
        if ok2:
            c = cv2.cornerSubPix(img, c, (5, 5), (-1, -1),
                                 (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-4))
            sub = c.reshape(-1, 2).astype(float).tolist()
        out.append({"sb": sb.reshape(-1, 2).astype(float).tolist() if ok else None, "subpix": sub})
    print(json.dumps(out))


if __name__ == "__main__":
    main(*sys.argv[2:]) if sys.argv[1] == "chessboard" else sys.exit("usage: chessboard COLS ROWS IMG...")
