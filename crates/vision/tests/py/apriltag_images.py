"""Write sheets of OpenCV-generated markers (cv2.aruco.generateImageMarker) and report the ids on
each sheet plus OpenCV's own detections of them.

usage: apriltag_images.py OUT_DIR DICT_NAME SIDE_PX
stdout: JSON [{"path": ..., "ids": [...], "opencv_ids": [...]}, ...]
"""
import json
import sys

import cv2
import numpy as np

out, name, side = sys.argv[1], sys.argv[2], int(sys.argv[3])
d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name))
n = d.bytesList.shape[0]
pitch = side + side // 2
cols, rows = 10, 7
det = cv2.aruco.ArucoDetector(d, cv2.aruco.DetectorParameters())
sheets = []
for s, start in enumerate(range(0, n, cols * rows)):
    ids = list(range(start, min(n, start + cols * rows)))
    img = np.full((rows * pitch + side // 2, cols * pitch + side // 2), 255, np.uint8)
    for k, i in enumerate(ids):
        r, c = divmod(k, cols)
        y, x = side // 2 + r * pitch, side // 2 + c * pitch
        img[y:y + side, x:x + side] = cv2.aruco.generateImageMarker(d, i, side, borderBits=1)
    path = f"{out}/{name}_{s:02d}.png"
    cv2.imwrite(path, img)
    _, found, _ = det.detectMarkers(img)
    sheets.append({"path": path, "ids": ids, "opencv_ids": sorted(int(v) for v in (found.flatten() if found is not None else []))})
print(json.dumps(sheets))
