#!/usr/bin/env python3
"""The network calibration's acceptance on independent simulated rooms, end to
end through the command line: simulate-network (6 x 5 x 3 m, 8 sensors, a
3-LED wand 60 s at 50 Hz, a static frame, 40 dB, 3 % bad frames), then
calibrate-network from no guess, then locate --rig on the held-out emitters
with the calibrated rig and with the true one, and evaluate.

    python3 crates/psdcal-network/scripts/acceptance.py [PSDCAL] [SEEDS...]

Prints, per seed: the held-out RMS with the calibrated rig and with the true
poses (and their ratio, to be <= 1.25), the worst sensor position error (mm,
< 5) and rotation error (deg, < 0.1), the RMS of error/sigma over every
sensor coordinate (0.4 .. 2.5), and the calibration's wall time."""

import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def rot(v):
    th = math.sqrt(sum(x * x for x in v))
    if th < 1e-15:
        return [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    k = [x / th for x in v]
    K = [[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]]
    KK = [[sum(K[i][m] * K[m][j] for m in range(3)) for j in range(3)] for i in range(3)]
    return [[(1 if i == j else 0) + math.sin(th) * K[i][j] + (1 - math.cos(th)) * KK[i][j]
             for j in range(3)] for i in range(3)]


def angle_deg(a, b):
    ra, rb = rot(a), rot(b)
    tr = sum(ra[i][k] * rb[i][k] for i in range(3) for k in range(3))
    return math.degrees(math.acos(max(-1.0, min(1.0, (tr - 1) / 2))))


def run(psdcal, seed, root):
    d = Path(root) / f"room{seed}"
    sh = lambda *a: subprocess.run([psdcal, *a], cwd=d, check=True, capture_output=True, text=True)
    subprocess.run([psdcal, "simulate-network", "--out", str(d), "--seed", str(seed), "-q"], check=True)
    t0 = time.time()
    sh("calibrate-network", "--sensors", "sensors.csv", "--wand", "wand.csv", "--frame", "frame.csv",
       "--observations", "network_points.csv", "--out", "rig.json", "-q")
    wall = time.time() - t0
    sigma = json.load(open(d / "rig.json"))["point_sigma_mm"]
    rms = {}
    for rig in ["rig.json", "true_rig.json"]:
        sh("locate", "--rig", rig, "--points", "rig_points.csv", "--out", f"est_{rig}.csv",
           "--point-sigma", str(sigma), "-q")
        out = sh("evaluate", "--truth", "truth.csv", "--estimates", f"est_{rig}.csv", "--json").stdout
        rms[rig] = json.loads(out)["rms_mm"]
    truth = json.load(open(d / "network_truth.json"))["sensors"]
    est = json.load(open(d / "rig.json"))["sensors"]
    worst_mm = worst_deg = 0.0
    z2 = []
    for t, e in zip(truth, est):
        dp = [e["position_world_mm"][i] - t["world_from_sensor"]["t_mm"][i] for i in range(3)]
        cov = e["position_world_covariance_mm2"]
        worst_mm = max(worst_mm, math.sqrt(sum(x * x for x in dp)))
        worst_deg = max(worst_deg, angle_deg(t["sensor_from_world"]["rvec"], e["sensor_from_world"]["rvec"]))
        z2 += [dp[i] ** 2 / cov[i][i] for i in range(3)]
    z = math.sqrt(sum(z2) / len(z2))
    ratio = rms["rig.json"] / rms["true_rig.json"]
    ok = ratio <= 1.25 and worst_mm < 5 and worst_deg < 0.1 and 0.4 <= z <= 2.5
    print(f"seed {seed}: held-out RMS {rms['rig.json']:.3f} mm (true poses {rms['true_rig.json']:.3f} mm, "
          f"ratio {ratio:.3f}); worst sensor {worst_mm:.3f} mm, {worst_deg:.4f} deg; RMS error/sigma "
          f"{z:.2f}; calibration {wall:.2f} s wall; {'ok' if ok else 'FAIL'}", flush=True)
    return ok


def main():
    psdcal = sys.argv[1] if len(sys.argv) > 1 else "target/release/psdcal"
    seeds = [int(s) for s in sys.argv[2:]] or [1, 2, 3, 4, 5]
    psdcal = str(Path(psdcal).resolve())
    with tempfile.TemporaryDirectory() as root:
        results = [run(psdcal, s, root) for s in seeds]
    sys.exit(0 if all(results) else 1)


if __name__ == "__main__":
    main()
