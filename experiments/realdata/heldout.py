"""Leave-one-image-out held-out angle error of psdcal against OpenCV and mrcal
on the real data sets under data/real/*/.

For every data set (a folder with template.csv, observations.csv, pixels.csv)
and every image i:

1. calibrate each method on all the other images:
   - opencv5: cv2.calibrateCamera, default model (fx, fy, cx, cy, k1, k2, p1,
     p2, k3) on pixels.csv (criteria raised to 200 iterations / 1e-15);
   - mrcal4, mrcal8: mrcal.optimize with LENSMODEL_OPENCV4 / LENSMODEL_OPENCV8
     on the same pixels and the known (flat) board, seeded from the OpenCV
     solution of the same fold (intrinsics and board poses); mrcal's default
     regularisation is kept, its outlier rejection is switched off (no method
     here rejects points), the board warp is not fitted;
   - psdcal: `psdcal calibrate` with its defaults on observations.csv without
     image i (sensor sizes --lx/--ly from sensor.txt or the built-in table);
2. turn image i's detected points into the calibrated model's rays
   (cv2.undistortPointsIter; mrcal.unproject; psdcal_model.ray for psdcal);
   a ray counts as answered when it is finite and, for the peers, projects
   back onto its pixel within 1e-3 px, for psdcal when the point is inside the
   calibration's valid_region (docs/formats.md);
3. fit image i's board pose (Rodrigues vector + translation) to the answered
   rays by minimising the sum of squared angles between each ray and the
   direction to R X + t (scipy least_squares, started from cv2.solvePnP on
   the rays with an identity camera); each point's held-out error is its angle.

Reported per set and method: RMS of the held-out angles (degrees) over all
answered points, the answered count, failed calibrations and pose fits. For
psdcal also: its σ of f, cx, cy on the full set (calibration.json "std",
default uncertainty = jackknife-raised; and, from a second run with
--uncertainty linear, the analytic σ) divided by the jackknife standard error
of the leave-one-image-out estimates, SE = sqrt((n-1)/n Σ (θ_i - θ̄)²); and
OpenCV's full-set fx, fy, cx, cy against psdcal's (in pixels of the
fictitious 5 µm sensor), the difference in units of psdcal's σ.

Run (from the repository root; /usr/bin/python3 has numpy, scipy, cv2, mrcal):

    /usr/bin/python3 experiments/realdata/heldout.py --psdcal target/release/psdcal
    /usr/bin/python3 experiments/realdata/heldout.py --sets pjlab_wideangle --max-images 4

--max-images N only holds out the first N images of a set (each calibration
still uses all the other images); the jackknife ratios are then marked partial.
Results: markdown tables on stdout and JSON at --json (default /tmp/heldout.json).
"""

import argparse
import csv
import json
import multiprocessing
import os
import shutil
import subprocess
import sys
import tempfile
import time

import cv2
import mrcal
import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import psdcal_model  # noqa: E402

PITCH_MM = 0.005
DEFAULT_SENSOR = {"pjlab_wideangle": (9.6, 6.0),
                  "niftycal_lap_left": (9.6, 2.7),
                  "niftycal_lap_right": (9.6, 2.7)}
METHODS = ["opencv5", "mrcal4", "mrcal8", "psdcal"]
PEERS = ["opencv5", "mrcal4", "mrcal8"]
ROUNDTRIP_PX = 1e-3
REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))


# ---------------------------------------------------------------- data

def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def sensor_size(set_dir, name):
    """(lx, ly) in mm: sensor.txt ('lx ly') when present, else the table."""
    path = os.path.join(set_dir, "sensor.txt")
    if os.path.exists(path):
        with open(path) as f:
            lx, ly = (float(v) for v in f.read().split()[:2])
        return lx, ly
    return DEFAULT_SENSOR[name]


def load_set(set_dir):
    """The template and the per-image points of a data set."""
    name = os.path.basename(os.path.normpath(set_dir))
    template = {int(r["led"]): (float(r["X_mm"]), float(r["Y_mm"]))
                for r in read_rows(os.path.join(set_dir, "template.csv"))}
    obs = read_rows(os.path.join(set_dir, "observations.csv"))
    pix = {(r["image"], int(r["led"])): (float(r["u_px"]), float(r["v_px"]))
           for r in read_rows(os.path.join(set_dir, "pixels.csv"))}
    images = []
    per = {}
    for r in obs:
        im = r["image"]
        if im not in per:
            images.append(im)
            per[im] = {"led": [], "mm": [], "px": []}
        led = int(r["led"])
        per[im]["led"].append(led)
        per[im]["mm"].append((float(r["x_mm"]), float(r["y_mm"])))
        per[im]["px"].append(pix[(im, led)])
    for im in images:
        d = per[im]
        d["led"] = np.array(d["led"])
        d["mm"] = np.array(d["mm"])
        d["px"] = np.array(d["px"])
        d["board"] = np.array([(*template[l], 0.0) for l in d["led"]])
    lx, ly = sensor_size(set_dir, name)
    return {"name": name, "dir": set_dir, "template": template, "images": images,
            "per": per, "lx": lx, "ly": ly,
            "size_px": (int(round(lx / PITCH_MM)), int(round(ly / PITCH_MM)))}


def board_grid(template):
    """Grid layout of the template (mrcal's board): spacing, width, height and
    each led's (row, col)."""
    xy = np.array(list(template.values()))
    xs, ys = np.unique(xy[:, 0]), np.unique(xy[:, 1])
    spacing = float(np.min(np.diff(xs)))
    if not np.allclose(np.min(np.diff(ys)), spacing):
        raise ValueError("template is not a square grid")
    w = int(round((xs[-1] - xs[0]) / spacing)) + 1
    h = int(round((ys[-1] - ys[0]) / spacing)) + 1
    cell = {}
    for led, (x, y) in template.items():
        c, r = (x - xs[0]) / spacing, (y - ys[0]) / spacing
        if abs(c - round(c)) > 1e-9 or abs(r - round(r)) > 1e-9:
            raise ValueError("template point off the grid")
        cell[led] = (int(round(r)), int(round(c)))
    if xs[0] != 0 or ys[0] != 0:
        raise ValueError("template grid does not start at (0, 0)")
    return spacing, w, h, cell


# ---------------------------------------------------------------- pose fit

def angles_rad(rays, points_cam):
    """Angle between rays (a, b, 1) and the directions to points_cam."""
    d = np.column_stack([rays, np.ones(len(rays))])
    cross = np.linalg.norm(np.cross(d, points_cam), axis=1)
    dot = np.sum(d * points_cam, axis=1)
    return np.arctan2(cross, dot)


def fit_pose(rays, board):
    """Board pose minimising the squared angles to the rays. Returns the
    per-point angles (rad) and whether the fit converged."""
    obj = np.ascontiguousarray(board, dtype=np.float64)
    img = np.ascontiguousarray(rays, dtype=np.float64).reshape(-1, 1, 2)
    start = None
    for flag in (cv2.SOLVEPNP_IPPE, cv2.SOLVEPNP_ITERATIVE):
        try:
            ok, rvec, tvec = cv2.solvePnP(obj, img, np.eye(3), None, flags=flag)
        except cv2.error:
            ok = False
        if ok:
            start = np.concatenate([rvec.ravel(), tvec.ravel()])
            break
    if start is None:
        return None, False

    def residuals(x):
        cam = Rotation.from_rotvec(x[:3]).apply(board) + x[3:]
        return angles_rad(rays, cam)

    r0 = residuals(start)
    sol = least_squares(residuals, start, jac="3-point", x_scale="jac", method="trf",
                        xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=500)
    ang = residuals(sol.x)
    converged = bool(sol.status > 0 and np.sum(ang ** 2) <= np.sum(r0 ** 2) * (1 + 1e-12)
                     and np.all(np.isfinite(ang)))
    return ang, converged


# ---------------------------------------------------------------- OpenCV

def opencv_calibrate(data, images):
    obj = [data["per"][im]["board"].astype(np.float32) for im in images]
    img = [data["per"][im]["px"].astype(np.float32).reshape(-1, 1, 2) for im in images]
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
    rms, K, dist, rvecs, tvecs = cv2.calibrateCamera(obj, img, data["size_px"], None, None,
                                                      flags=0, criteria=crit)
    return {"rms_px": float(rms), "K": K, "dist": dist.ravel()[:5],
            "rvecs": [r.ravel() for r in rvecs], "tvecs": [t.ravel() for t in tvecs]}


def opencv_rays(cal, px):
    src = px.reshape(-1, 1, 2).astype(np.float64)
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
    if hasattr(cv2, "undistortPointsIter"):
        und = cv2.undistortPointsIter(src, cal["K"], cal["dist"], None, None, crit)
    else:
        und = cv2.undistortPoints(src, cal["K"], cal["dist"])
    rays = und.reshape(-1, 2)
    back, _ = cv2.projectPoints(np.column_stack([rays, np.ones(len(rays))]),
                                np.zeros(3), np.zeros(3), cal["K"], cal["dist"])
    err = np.linalg.norm(back.reshape(-1, 2) - px, axis=1)
    ok = np.all(np.isfinite(rays), axis=1) & (err < ROUNDTRIP_PX)
    return rays, ok


# ---------------------------------------------------------------- mrcal

def mrcal_calibrate(data, images, lensmodel, seed):
    spacing, w, h, cell = board_grid(data["template"])
    n = len(images)
    obs = np.zeros((n, h, w, 3))
    obs[..., 2] = -1.0  # missing corners: outliers
    for k, im in enumerate(images):
        d = data["per"][im]
        for led, (u, v) in zip(d["led"], d["px"]):
            r, c = cell[led]
            obs[k, r, c] = (u, v, 1.0)
    K, dist = seed["K"], seed["dist"]  # k1 k2 p1 p2 k3
    core = [K[0, 0], K[1, 1], K[0, 2], K[1, 2]]
    if lensmodel == "LENSMODEL_OPENCV4":
        intr = np.array(core + list(dist[:4]), dtype=float)
    else:
        intr = np.array(core + list(dist[:5]) + [0.0, 0.0, 0.0], dtype=float)
    frames = np.array([np.concatenate([r, t]) for r, t in zip(seed["rvecs"], seed["tvecs"])],
                      dtype=float)
    idx = np.array([(k, 0, -1) for k in range(n)], dtype=np.int32)
    intr = intr.reshape(1, -1).copy()
    stats = mrcal.optimize(intr, np.zeros((0, 6)), frames, None, obs, idx, None, None,
                           lensmodel,
                           imagersizes=np.array([data["size_px"]], dtype=np.int32),
                           calibration_object_spacing=spacing,
                           do_optimize_intrinsics_core=True,
                           do_optimize_intrinsics_distortions=True,
                           do_optimize_frames=True,
                           do_optimize_extrinsics=False,
                           do_optimize_calobject_warp=False,
                           do_apply_outlier_rejection=False,
                           do_apply_regularization=True,
                           point_min_range=1.0, point_max_range=1e6)
    # mrcal's RMS is per coordinate; x sqrt(2) makes it per point like OpenCV's
    return {"lensmodel": lensmodel, "intrinsics": intr[0].copy(),
            "rms_px": float(stats.get("rms_reproj_error__pixels", np.nan)) * np.sqrt(2)}


def mrcal_rays(cal, px):
    v = mrcal.unproject(np.ascontiguousarray(px, dtype=float), cal["lensmodel"],
                        cal["intrinsics"])
    with np.errstate(all="ignore"):
        rays = v[:, :2] / v[:, 2:3]
        ok = np.all(np.isfinite(v), axis=1) & (v[:, 2] > 0)
        back = mrcal.project(np.column_stack([rays, np.ones(len(rays))]), cal["lensmodel"],
                             cal["intrinsics"])
        err = np.linalg.norm(back - px, axis=1)
    ok &= np.isfinite(err) & (err < ROUNDTRIP_PX)
    return rays, ok


# ---------------------------------------------------------------- psdcal

def write_subset(set_dir, exclude, path):
    """observations.csv without the image `exclude` (None: all), same header."""
    with open(os.path.join(set_dir, "observations.csv"), newline="") as f, \
            open(path, "w", newline="") as g:
        rd, wr = csv.reader(f), csv.writer(g)
        header = next(rd)
        wr.writerow(header)
        col = header.index("image")
        for row in rd:
            if row and row[col] != exclude:
                wr.writerow(row)


def psdcal_calibrate(binary, data, exclude, workdir, extra=()):
    """Run psdcal calibrate; returns (calibration json or None, status dict)."""
    obs = os.path.join(workdir, "obs_subset.csv")
    out = os.path.join(workdir, "cal.json")
    write_subset(data["dir"], exclude, obs)
    if os.path.exists(out):
        os.remove(out)
    cmd = [binary, "calibrate", "-t", os.path.join(data["dir"], "template.csv"), "-o", obs,
           "--lx", repr(data["lx"]), "--ly", repr(data["ly"]), "--out", out, *extra]
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True)
    status = {"rc": p.returncode, "seconds": round(time.time() - t0, 2),
              "warnings": [l.strip() for l in p.stderr.splitlines() if "warning" in l.lower()]}
    if p.returncode != 0 or not os.path.exists(out):
        status["error"] = (p.stderr.strip() or p.stdout.strip())[-2000:]
        return None, status
    with open(out) as f:
        cal = json.load(f)
    status["free"] = [k for s in cal.get("stages", []) for k in s.get("estimated", [])]
    status["diagnostics"] = [d.get("code") for d in cal.get("diagnostics", [])]
    return cal, status


KNOWN_PARAMETERS = {"f", "cx", "cy", "skew", "k1", "k2", "k3", "p1", "p2", "l1", "l2", "a"}
KNOWN_STAGES = {"psd_radial", "aspect", "lens", "pinhole"}


def check_model_terms(cal):
    """Terms of the json that psdcal_model.ray does not implement (must be empty)."""
    extra = sorted(set(cal["parameters"]) - KNOWN_PARAMETERS)
    extra += ["stage:" + s["kind"] for s in cal.get("stages", []) if s["kind"] not in KNOWN_STAGES]
    return extra


def inside_valid_region(cal, mm):
    """docs/formats.md: inside when rho < min(r_i, r_i+1) (1 - 0.001)."""
    vr = cal.get("valid_region")
    if not vr:
        return np.ones(len(mm), dtype=bool)
    c = np.array(vr["centre_mm"])
    r = np.array(vr["radius_mm"])
    n = int(vr["rays"])
    d = mm - c
    rho = np.hypot(d[:, 0], d[:, 1])
    ang = np.mod(np.arctan2(d[:, 1], d[:, 0]), 2 * np.pi)
    i = np.floor(ang / (2 * np.pi / n)).astype(int) % n
    lim = np.minimum(r[i], r[(i + 1) % n]) * (1 - 0.001)
    return rho < lim


def psdcal_rays(cal, mm):
    p = dict(cal["parameters"])
    p.setdefault("a", 0.0)
    rays = psdcal_model.ray(p, mm)
    ok = np.all(np.isfinite(rays), axis=1) & inside_valid_region(cal, mm)
    return rays, ok


# ---------------------------------------------------------------- one fold

def run_fold(job):
    """Hold out image `held`, calibrate every method on the rest, score `held`."""
    data, held, binary = job
    train = [im for im in data["images"] if im != held]
    d = data["per"][held]
    out = {"image": held, "points": len(d["led"]), "methods": {}}
    cals = {}
    try:
        cals["opencv5"] = opencv_calibrate(data, train)
    except cv2.error as e:
        out["methods"]["opencv5"] = {"error": str(e)[:300]}
    for name, lm in (("mrcal4", "LENSMODEL_OPENCV4"), ("mrcal8", "LENSMODEL_OPENCV8")):
        if "opencv5" not in cals:
            out["methods"][name] = {"error": "no OpenCV seed"}
            continue
        try:
            cals[name] = mrcal_calibrate(data, train, lm, cals["opencv5"])
        except Exception as e:  # mrcal raises plain exceptions
            out["methods"][name] = {"error": repr(e)[:300]}
    workdir = tempfile.mkdtemp(prefix="heldout-")
    try:
        cal, status = psdcal_calibrate(binary, data, held, workdir)
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    out["psdcal_status"] = status
    if cal is not None:
        cals["psdcal"] = cal
        out["psdcal_estimate"] = {k: cal["parameters"][k] for k in ("f", "cx", "cy")}
        out["psdcal_unmodelled_terms"] = check_model_terms(cal)
    else:
        out["methods"]["psdcal"] = {"error": "rc=%d: %s" % (status["rc"], status.get("error", ""))}

    for m in METHODS:
        if m not in cals:
            continue
        if m == "opencv5":
            rays, ok = opencv_rays(cals[m], d["px"])
        elif m == "psdcal":
            rays, ok = psdcal_rays(cals[m], d["mm"])
        else:
            rays, ok = mrcal_rays(cals[m], d["px"])
        res = {"answered": int(ok.sum()), "angles_deg": [], "pose_converged": False}
        if m != "psdcal":
            res["train_rms_px"] = cals[m]["rms_px"]
        if ok.sum() >= 4:
            ang, conv = fit_pose(rays[ok], d["board"][ok])
            if ang is not None:
                res["angles_deg"] = np.degrees(ang).tolist()
            else:
                res["answered"] = 0
            res["pose_converged"] = conv
        else:
            res["answered"] = 0
        out["methods"][m] = res
    return out


# ---------------------------------------------------------------- full set

def psd_sigma_px(cal, lx, ly):
    """psdcal's f, fy, cx, cy and their σ in pixels (fy = f (1 + a))."""
    p, std = cal["parameters"], cal.get("std", {})
    cov = cal.get("covariance")
    a = p.get("a", 0.0)
    f = p["f"]
    val = {"fx": f / PITCH_MM, "fy": f * (1 + a) / PITCH_MM,
           "cx": (p["cx"] + lx / 2) / PITCH_MM - 0.5, "cy": (p["cy"] + ly / 2) / PITCH_MM - 0.5}
    sig = {"fx": std["f"] / PITCH_MM, "cx": std["cx"] / PITCH_MM, "cy": std["cy"] / PITCH_MM}
    note = ""
    if "a" in std and cov is not None:
        names = cov["parameters"]
        C = np.array(cov["matrix"])
        i, j = names.index("f"), names.index("a")
        var = ((1 + a) ** 2 * C[i, i] + f ** 2 * C[j, j] + 2 * f * (1 + a) * C[i, j])
        sig["fy"] = np.sqrt(var) / PITCH_MM
        note = "σ(fy) from f, a and their covariance"
    elif "a" in std:
        sig["fy"] = np.hypot((1 + a) * std["f"], f * std["a"]) / PITCH_MM
        note = "σ(fy) from σ(f), σ(a) without their covariance"
    else:
        sig["fy"] = (1 + a) * std["f"] / PITCH_MM
        note = "a not estimated: σ(fy) = (1 + a) σ(f)"
    return val, sig, note


def aoa_crosscheck(binary, cal_path, data, workdir):
    """psdcal's own rays (`psdcal aoa`) of every measured point against
    psdcal_model.ray and the valid-region test: max angle (deg) between them
    and the statuses psdcal gives."""
    pts = os.path.join(workdir, "points.csv")
    mm = np.vstack([data["per"][im]["mm"] for im in data["images"]])
    np.savetxt(pts, mm, delimiter=",", header="x_mm,y_mm", comments="", fmt="%.10g")
    aoa = os.path.join(workdir, "aoa.csv")
    p = subprocess.run([binary, "aoa", "-q", "-c", cal_path, "-p", pts, "--out", aoa],
                       capture_output=True, text=True)
    if p.returncode != 0:
        return {"error": p.stderr.strip()[-500:]}
    rows = read_rows(aoa)
    status = np.array([r["status"] for r in rows])
    with open(cal_path) as f:
        cal = json.load(f)
    rays, ok = psdcal_rays(cal, mm)
    good = status != "outside_valid_region"
    ang = []
    for r, ray, g in zip(rows, rays, good):
        if g and r["ray_z"] not in ("", None):
            v = np.array([float(r["ray_x"]), float(r["ray_y"]), float(r["ray_z"])])
            ang.append(angles_rad(ray[None, :], v[None, :])[0])
    return {"points": len(rows),
            "statuses": {k: int(np.sum(status == k)) for k in np.unique(status)},
            "max_angle_deg_vs_python": float(np.degrees(np.max(ang))) if ang else None,
            "valid_region_agrees": bool(np.all(ok == good))}


def full_set(data, binary):
    out = {}
    cv = opencv_calibrate(data, data["images"])
    K = cv["K"]
    out["opencv"] = {"fx": K[0, 0], "fy": K[1, 1], "cx": K[0, 2], "cy": K[1, 2],
                     "dist": cv["dist"].tolist(), "rms_px": cv["rms_px"]}
    for label, extra in (("default", ()), ("linear", ("--uncertainty", "linear"))):
        workdir = tempfile.mkdtemp(prefix="heldout-full-")
        try:
            cal, status = psdcal_calibrate(binary, data, None, workdir, extra)
            if cal is not None and label == "default":
                out["aoa_crosscheck"] = aoa_crosscheck(binary, os.path.join(workdir, "cal.json"),
                                                       data, workdir)
        finally:
            shutil.rmtree(workdir, ignore_errors=True)
        entry = {"status": status}
        if cal is not None:
            entry["parameters"] = cal["parameters"]
            entry["std"] = cal.get("std", {})
            entry["uncertainty"] = cal.get("fit", {}).get("uncertainty")
            entry["unmodelled_terms"] = check_model_terms(cal)
            if label == "default":
                val, sig, note = psd_sigma_px(cal, data["lx"], data["ly"])
                entry["px"] = val
                entry["sigma_px"] = sig
                entry["sigma_fy_note"] = note
                entry["skew_mm"] = cal["parameters"].get("skew", 0.0)
        out["psdcal_" + label] = entry
    return out


# ---------------------------------------------------------------- summary

def rms(values):
    v = np.asarray(values, dtype=float)
    return float(np.sqrt(np.mean(v ** 2))) if len(v) else float("nan")


def warning_kinds(warnings):
    """Warnings grouped by their text up to the first digit or '(': count and an example."""
    kinds = {}
    for w in warnings:
        cut = min([i for i, ch in enumerate(w) if ch.isdigit() or ch == "("] + [len(w)])
        key = w[:cut].strip()
        k = kinds.setdefault(key, {"count": 0, "example": w})
        k["count"] += 1
    return kinds


def summarise(data, folds, full, partial):
    s = {"set": data["name"], "images": len(data["images"]), "folds": len(folds),
         "points": int(sum(f["points"] for f in folds)), "partial": partial,
         "lx": data["lx"], "ly": data["ly"], "size_px": data["size_px"], "methods": {}}
    for m in METHODS:
        angles = [a for f in folds for a in f["methods"].get(m, {}).get("angles_deg", [])]
        fails = [f["image"] for f in folds if "error" in f["methods"].get(m, {})]
        noconv = [f["image"] for f in folds
                  if m in f["methods"] and "error" not in f["methods"][m]
                  and not f["methods"][m].get("pose_converged")]
        s["methods"][m] = {"rms_deg": rms(angles), "answered": len(angles),
                           "failed_calibrations": fails, "pose_not_converged": noconv,
                           "max_deg": float(np.max(angles)) if angles else float("nan")}
    best_peer = min((s["methods"][m]["rms_deg"] for m in PEERS
                     if np.isfinite(s["methods"][m]["rms_deg"])), default=float("nan"))
    s["psdcal_over_best_peer"] = s["methods"]["psdcal"]["rms_deg"] / best_peer

    # jackknife of psdcal's leave-one-out estimates
    est = [f["psdcal_estimate"] for f in folds if "psdcal_estimate" in f]
    n = len(est)
    s["jackknife_n"] = n
    s["sigma_over_se_jack"] = {}
    s["linear_sigma_over_se_jack"] = {}
    s["se_jack_mm"] = {}
    for k in ("f", "cx", "cy"):
        th = np.array([e[k] for e in est])
        se = float(np.sqrt((n - 1) / n * np.sum((th - th.mean()) ** 2))) if n > 1 else float("nan")
        s["se_jack_mm"][k] = se
        for label, key in (("default", "sigma_over_se_jack"), ("linear", "linear_sigma_over_se_jack")):
            std = full.get("psdcal_" + label, {}).get("std", {})
            s[key][k] = std[k] / se if k in std and se > 0 else float("nan")

    # OpenCV against psdcal on the full set
    s["delta_over_sigma"] = {}
    pd = full.get("psdcal_default", {})
    if "px" in pd:
        for k in ("fx", "fy", "cx", "cy"):
            s["delta_over_sigma"][k] = abs(full["opencv"][k] - pd["px"][k]) / pd["sigma_px"][k]

    # psdcal run statistics
    st = [f["psdcal_status"] for f in folds]
    s["psdcal_runs"] = {
        "nonzero_exit": [f["image"] for f in folds if f["psdcal_status"]["rc"] != 0],
        "runs_with_warnings": sum(1 for x in st if x.get("warnings")),
        "warning_kinds": warning_kinds([w for x in st for w in x.get("warnings", [])]),
        "diagnostic_codes": {c: sum(1 for x in st if c in x.get("diagnostics", []))
                             for c in sorted({c for x in st for c in x.get("diagnostics", [])})},
        "free_sets": sorted({",".join(x.get("free", [])) for x in st if x.get("free")}),
        "seconds_mean": float(np.mean([x["seconds"] for x in st])),
        "unmodelled_terms": sorted({t for f in folds for t in f.get("psdcal_unmodelled_terms", [])}),
    }
    return s


def fmt(x, spec=".4f"):
    return "n/a" if x is None or not np.isfinite(x) else format(x, spec)


def print_set(s, full, folds):
    print("\n## %s (%d images, %d held-out folds%s, sensor %.3g x %.3g mm = %d x %d px)\n"
          % (s["set"], s["images"], s["folds"], ", PARTIAL" if s["partial"] else "",
             s["lx"], s["ly"], *s["size_px"]))
    print("| method | held-out RMS (deg) | max (deg) | answered / points | failed calibrations "
          "| pose fits not converged | mean training RMS per point (px) |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for m in METHODS:
        r = s["methods"][m]
        tr = [f["methods"][m]["train_rms_px"] for f in folds
              if "train_rms_px" in f["methods"].get(m, {})]
        print("| %s | %s | %s | %d / %d | %d | %d | %s |"
              % (m, fmt(r["rms_deg"], ".5f"), fmt(r["max_deg"], ".4f"), r["answered"],
                 s["points"], len(r["failed_calibrations"]), len(r["pose_not_converged"]),
                 fmt(np.mean(tr) if tr else float("nan"), ".4f")))
    print("\npsdcal ÷ best peer: %s" % fmt(s["psdcal_over_best_peer"], ".3f"))
    pd = full.get("psdcal_default", {})
    if "parameters" in pd:
        print("\npsdcal full set: uncertainty %s, free %s, skew %.4g mm; jackknife over %d folds"
              % (pd.get("uncertainty"), ",".join(pd["status"].get("free", [])), pd["skew_mm"],
                 s["jackknife_n"]))
        print("\n| | f | cx | cy |\n| --- | --- | --- | --- |")
        print("| σ default (mm) | %s |" % " | ".join(fmt(pd["std"][k], ".3e") for k in ("f", "cx", "cy")))
        pl = full.get("psdcal_linear", {})
        if "std" in pl:
            print("| σ linear (mm) | %s |" % " | ".join(fmt(pl["std"][k], ".3e") for k in ("f", "cx", "cy")))
        print("| SE_jack (mm) | %s |" % " | ".join(fmt(s["se_jack_mm"][k], ".3e") for k in ("f", "cx", "cy")))
        print("| σ default / SE_jack | %s |" % " | ".join(fmt(s["sigma_over_se_jack"][k], ".2f") for k in ("f", "cx", "cy")))
        print("| σ linear / SE_jack | %s |" % " | ".join(fmt(s["linear_sigma_over_se_jack"][k], ".2f") for k in ("f", "cx", "cy")))
        print("\n| px | fx | fy | cx | cy |\n| --- | --- | --- | --- | --- |")
        oc = full["opencv"]
        print("| OpenCV | %s |" % " | ".join(fmt(oc[k], ".3f") for k in ("fx", "fy", "cx", "cy")))
        print("| psdcal | %s |" % " | ".join(fmt(pd["px"][k], ".3f") for k in ("fx", "fy", "cx", "cy")))
        print("| psdcal σ | %s |" % " | ".join(fmt(pd["sigma_px"][k], ".3f") for k in ("fx", "fy", "cx", "cy")))
        print("| \\|Δ\\|/σ | %s |" % " | ".join(fmt(s["delta_over_sigma"][k], ".2f") for k in ("fx", "fy", "cx", "cy")))
        print("\n(%s; OpenCV full-set RMS %.4f px)" % (pd["sigma_fy_note"], oc["rms_px"]))
    else:
        print("\npsdcal full-set calibration FAILED: %s" % pd.get("status"))
    r = s["psdcal_runs"]
    print("\npsdcal leave-one-out runs: non-zero exits %s; mean %.1f s; fitted sets %s; "
          "runs with warnings %d of %d; diagnostic codes (runs) %s"
          % (r["nonzero_exit"] or "none", r["seconds_mean"], r["free_sets"],
             r["runs_with_warnings"], len(folds), r["diagnostic_codes"] or "none"))
    for k in r["warning_kinds"].values():
        print("  - %d x, e.g.: %s" % (k["count"], k["example"][:600]))
    for m in METHODS:
        for im in s["methods"][m]["failed_calibrations"]:
            print("  - %s failed on fold %s: %s" % (m, im, next(
                f["methods"][m]["error"] for f in folds if f["image"] == im)[:300]))
    ac = full.get("aoa_crosscheck")
    if ac:
        print("\npsdcal aoa vs psdcal_model.ray on all %s points (full-set calibration): "
              "max angle %s deg, statuses %s, valid-region test agrees: %s"
              % (ac.get("points"), fmt(ac.get("max_angle_deg_vs_python"), ".2e"),
                 ac.get("statuses"), ac.get("valid_region_agrees")))
    if r["unmodelled_terms"]:
        print("  !! calibration.json terms psdcal_model.ray does not implement: %s"
              % r["unmodelled_terms"])


def print_summary(summaries):
    print("\n## Summary (held-out RMS angle, degrees)\n")
    print("| set | images | points | OpenCV5 | mrcal4 | mrcal8 | psdcal | psdcal ÷ best peer "
          "| answered cv/m4/m8/psd | σ/SE_jack f, cx, cy | \\|Δ\\|/σ fx, fy, cx, cy |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for s in summaries:
        m = s["methods"]
        print("| %s%s | %d | %d | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            s["set"], " (partial)" if s["partial"] else "", s["images"], s["points"],
            *(fmt(m[k]["rms_deg"], ".5f") for k in METHODS),
            fmt(s["psdcal_over_best_peer"], ".3f"),
            "/".join(str(m[k]["answered"]) for k in METHODS),
            ", ".join(fmt(s["sigma_over_se_jack"][k], ".2f") for k in ("f", "cx", "cy")),
            ", ".join(fmt(s["delta_over_sigma"].get(k), ".2f") for k in ("fx", "fy", "cx", "cy"))))
    print("\n(σ/SE_jack with psdcal's analytic σ, --uncertainty linear: %s)" % "; ".join(
        "%s %s" % (s["set"], ", ".join(fmt(s["linear_sigma_over_se_jack"][k], ".2f")
                                        for k in ("f", "cx", "cy"))) for s in summaries))


def to_jsonable(x):
    if isinstance(x, dict):
        return {str(k): to_jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [to_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return to_jsonable(x.tolist())
    if isinstance(x, (np.floating, float)):
        return float(x) if np.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--psdcal", default="/tmp/psdcal-h30a", help="psdcal binary")
    ap.add_argument("--data", default=os.path.join(REPO, "data", "real"))
    ap.add_argument("--sets", default=None, help="comma-separated set names")
    ap.add_argument("--max-images", type=int, default=None,
                    help="hold out only the first N images of each set")
    ap.add_argument("--json", default="/tmp/heldout.json")
    ap.add_argument("--processes", type=int, default=2, help="at most 2")
    args = ap.parse_args()
    binary = os.path.abspath(args.psdcal)
    names = sorted(d for d in os.listdir(args.data)
                   if os.path.exists(os.path.join(args.data, d, "observations.csv")))
    if args.sets:
        want = args.sets.split(",")
        names = [n for n in names if n in want]
    t_start = time.time()
    summaries, report = [], {"command": " ".join(sys.argv), "psdcal": binary, "sets": {}}
    procs = max(1, min(2, args.processes))
    with multiprocessing.Pool(procs) as pool:
        for name in names:
            t0 = time.time()
            data = load_set(os.path.join(args.data, name))
            held = data["images"][:args.max_images] if args.max_images else data["images"]
            folds = pool.map(run_fold, [(data, im, binary) for im in held], chunksize=1)
            full = full_set(data, binary)
            s = summarise(data, folds, full, partial=len(held) < len(data["images"]))
            s["seconds"] = round(time.time() - t0, 1)
            print_set(s, full, folds)
            print("\n(%s: %.0f s)" % (name, s["seconds"]))
            sys.stdout.flush()
            summaries.append(s)
            report["sets"][name] = {"summary": s, "full_set": full, "folds": folds}
    print_summary(summaries)
    report["summary"] = summaries
    report["seconds"] = round(time.time() - t_start, 1)
    print("\ntotal run time %.0f s" % report["seconds"])
    with open(args.json, "w") as f:
        json.dump(to_jsonable(report), f, indent=1)
    print("wrote %s" % args.json)


if __name__ == "__main__":
    main()
