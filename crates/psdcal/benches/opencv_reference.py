"""OpenCV's calibrateCamera on the points `psdcal calibrate` fits, timed
against the whole `psdcal calibrate` process on the same files.

The issue "One engine" asks the whole process (read the files, start,
refine, covariance, diagnostics, write calibration.json) to take at most a
tenth of OpenCV's calibrateCamera on the same points. This script times:

- OpenCV: `cv2.calibrateCamera` alone, in this process (no file reading, no
  process start: favourable to OpenCV), with the model closest to psdcal's
  default fit (f with a fixed aspect ratio, centre, k1, k2; no tangential
  terms, k3 fixed). Points in mm are given to OpenCV as pixels of 1 µm on
  an image of the active area's size, so that its start (centre of the
  image, its homography-based focal length) sees the sensor's geometry.
- psdcal: the whole process, `psdcal -q calibrate -t T -o O --out C`, started
  from here with subprocess (the fork and exec of Python count against
  psdcal: unfavourable to it).

Each is run REPEATS times, the two alternating (so that the VM's drifting
load falls on both alike); the median and the minimum are printed, and the
ratio of the medians.

Run (from the repository root, after `cargo build --release`):

    target/release/psdcal simulate --lens 2 --snr 40 --images 12 --seed 3 --out /tmp/bench2
    python3 crates/psdcal/benches/opencv_reference.py /tmp/bench2 [PSDCAL_BINARY]
"""

import csv
import os
import statistics
import subprocess
import sys
import tempfile
import time

import cv2
import numpy as np

REPEATS = 60
PIXELS_PER_MM = 1000.0
SENSOR_MM = 9.0


def rows(path):
    with open(path, newline="") as f:
        lines = [line for line in f if line.strip() and not line.lstrip().startswith("#")]
    return list(csv.DictReader(lines))


def points(folder):
    template = {int(r["led"]): (float(r["X_mm"]), float(r["Y_mm"])) for r in rows(os.path.join(folder, "template.csv"))}
    images = {}
    for r in rows(os.path.join(folder, "observations.csv")):
        images.setdefault(r["image"], []).append((int(r["led"]), float(r["x_mm"]), float(r["y_mm"])))
    half = 0.5 * SENSOR_MM * PIXELS_PER_MM
    object_points, image_points = [], []
    for obs in images.values():
        object_points.append(np.array([[*template[led], 0.0] for led, _, _ in obs], np.float32))
        image_points.append(
            np.array([[x * PIXELS_PER_MM + half, y * PIXELS_PER_MM + half] for _, x, y in obs], np.float32)
        )
    return object_points, image_points


def timed(first, second):
    """Median and minimum of each of two runs, alternated REPEATS times."""
    times = ([], [])
    for _ in range(REPEATS):
        for run, out in ((first, times[0]), (second, times[1])):
            start = time.perf_counter()
            run()
            out.append(time.perf_counter() - start)
    return [(statistics.median(t), min(t)) for t in times]


def main():
    cv2.setNumThreads(1)
    folder = sys.argv[1]
    binary = sys.argv[2] if len(sys.argv) > 2 else "target/release/psdcal"
    object_points, image_points = points(folder)
    size = (int(SENSOR_MM * PIXELS_PER_MM), int(SENSOR_MM * PIXELS_PER_MM))
    flags = cv2.CALIB_FIX_ASPECT_RATIO | cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K3
    camera = np.eye(3)

    def opencv():
        cv2.calibrateCamera(object_points, image_points, size, camera.copy(), None, flags=flags)

    rms, k, dist, _, _ = cv2.calibrateCamera(object_points, image_points, size, camera.copy(), None, flags=flags)
    print(f"OpenCV {cv2.__version__}: f = {k[0, 0] / PIXELS_PER_MM:.4f} mm, RMS {rms / PIXELS_PER_MM * 1000:.3f} µm")
    with tempfile.TemporaryDirectory() as out:
        command = [
            binary, "-q", "calibrate",
            "-t", os.path.join(folder, "template.csv"),
            "-o", os.path.join(folder, "observations.csv"),
            "--out", os.path.join(out, "calibration.json"),
        ]
        (cv_median, cv_min), (ps_median, ps_min) = timed(
            opencv, lambda: subprocess.run(command, check=True)
        )
    print(f"OpenCV calibrateCamera: median {cv_median * 1e3:.2f} ms, min {cv_min * 1e3:.2f} ms")
    print(f"psdcal calibrate (whole process): median {ps_median * 1e3:.2f} ms, min {ps_min * 1e3:.2f} ms")
    print(f"psdcal / OpenCV (medians): {ps_median / cv_median:.3f}")


if __name__ == "__main__":
    main()
