"""Angles through psdcal's exported camera models, read by the real OpenCV,
mrcal and a YAML reader, against psdcal's own `aoa` answers.

Run by tests/export.rs with Debian's /usr/bin/python3:

    export_roundtrip.py AOA_CSV PITCH_UM LX_MM LY_MM TOL_DEG FORMAT=FILE...

FORMAT is opencv, mrcal or ros. For every row of AOA_CSV with status ok, the
measured point (x_mm, y_mm) becomes the pixel u = 1000 (x + Lx/2)/P - 0.5,
v = 1000 (y + Ly/2)/P - 0.5; each model unprojects it to a ray (x', y', 1)
and alpha = atan of its components is compared with alpha_x_deg, alpha_y_deg.
Prints one JSON line per file; exits 1 when an angle differs by more than
TOL_DEG (or a file does not load).
"""

import csv
import json
import math
import sys

import cv2
import mrcal
import numpy as np
import yaml


def read_aoa(path):
    points, alphas = [], []
    with open(path, newline="") as f:
        rows = csv.DictReader(line for line in f if not line.startswith("#"))
        for row in rows:
            if row["status"] != "ok":
                continue
            points.append((float(row["x_mm"]), float(row["y_mm"])))
            alphas.append((float(row["alpha_x_deg"]), float(row["alpha_y_deg"])))
    return np.array(points), np.array(alphas)


def opencv_rays(pixels, k, d):
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 10000, 1e-15)
    src = pixels.reshape(-1, 1, 2).astype(np.float64)
    out = cv2.undistortPointsIter(src, k, d, None, None, criteria)
    return out.reshape(-1, 2)


def rays_of(kind, path, pixels):
    if kind == "opencv":
        fs = cv2.FileStorage(path, cv2.FILE_STORAGE_READ)
        if not fs.isOpened():
            raise RuntimeError(f"OpenCV cannot open {path}")
        k = fs.getNode("camera_matrix").mat()
        d = fs.getNode("distortion_coefficients").mat()
        size = (fs.getNode("image_width").real(), fs.getNode("image_height").real())
        fs.release()
        if k is None or d is None or d.size != 8:
            raise RuntimeError(f"{path}: no camera_matrix or 8 distortion coefficients")
        return opencv_rays(pixels, k, d), size, "rational"
    if kind == "mrcal":
        model = mrcal.cameramodel(path)
        lensmodel, intrinsics = model.intrinsics()
        if lensmodel != "LENSMODEL_OPENCV8":
            raise RuntimeError(f"{path}: {lensmodel}, expected LENSMODEL_OPENCV8")
        v = mrcal.unproject(pixels, lensmodel, intrinsics)
        return v[:, :2] / v[:, 2:3], tuple(model.imagersize()), lensmodel
    if kind == "ros":
        with open(path) as f:
            info = yaml.safe_load(f)
        k = np.array(info["camera_matrix"]["data"], dtype=float).reshape(3, 3)
        d = np.array(info["distortion_coefficients"]["data"], dtype=float)
        model = info["distortion_model"]
        expected = {"plumb_bob": 5, "rational_polynomial": 8}
        if expected.get(model) != d.size:
            raise RuntimeError(f"{path}: {model} with {d.size} coefficients")
        for key in ("image_width", "image_height"):
            if not isinstance(info[key], int):
                raise RuntimeError(f"{path}: {key} is not an integer")
        return opencv_rays(pixels, k, d), (info["image_width"], info["image_height"]), model
    raise RuntimeError(f"unknown format {kind}")


def main():
    aoa_csv, pitch, lx, ly, tol = sys.argv[1:6]
    pitch, lx, ly, tol = float(pitch), float(lx), float(ly), float(tol)
    points, alphas = read_aoa(aoa_csv)
    if len(points) < 100:
        print(f"only {len(points)} answered points in {aoa_csv}", file=sys.stderr)
        return 1
    pixels = np.column_stack(
        [1000 * (points[:, 0] + lx / 2) / pitch - 0.5, 1000 * (points[:, 1] + ly / 2) / pitch - 0.5]
    )
    failed = False
    for spec in sys.argv[6:]:
        kind, path = spec.split("=", 1)
        rays, size, model = rays_of(kind, path, pixels)
        expected_size = (round(1000 * lx / pitch), round(1000 * ly / pitch))
        got = np.degrees(np.arctan(rays))
        err = np.abs(got - alphas)
        worst = int(np.argmax(err.max(axis=1)))
        result = {
            "format": kind,
            "model": model,
            "points": len(points),
            "max_deg": float(err.max()),
            "rms_deg": float(math.sqrt(np.mean(err**2))),
            "worst_at_mm": points[worst].tolist(),
            "image_size_ok": tuple(int(s) for s in size) == expected_size,
        }
        print(json.dumps(result))
        if not (result["max_deg"] <= tol and result["image_size_ok"]):
            failed = True
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
