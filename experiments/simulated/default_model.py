"""Acceptance checks of `psdcal calibrate`'s DEFAULT model choice (no --fit) on
simulated data, where the truth is known (truth.json of `psdcal simulate`).

Part A -- sigma coverage where the model is exact.
    Lens 1 and 2, --snr 40, images N in {9, 12, 16, 20}, seeds 1..K (default
    K = 50: 400 data sets), no --psd-distortion. Each data set is calibrated
    twice with psdcal's default model choice: once with the default
    uncertainty (jackknife-raised) and once with --uncertainty linear. For f,
    cx, cy: z = (estimate - truth) / sigma (sigma = calibration.json "std").
    Reported per lens and overall, for each uncertainty method: RMS of z per
    parameter, fraction with |z| <= 3, how often the model choice added a
    group beyond f,cx,cy,k1,k2 (and which), and failures (non-zero exit, with
    the error line). Target: RMS z in [0.7, 1.4]; >= 97 % within 3 sigma.

Part B -- angle-of-arrival accuracy of the default against explicit fits.
    Lens 1 and 2, --snr 40, 12 images, seeds 1..10, with and without
    --psd-distortion. Three calibrations per data set: the default; --fit
    f,cx,cy,k1,k2; --fit f,cx,cy,k1,k2,l1. Each is judged against the truth
    with psdcal's own measurement, `psdcal diff TRUTH.json CAL.json --json`:
    TRUTH.json is a version-1 calibration.json holding truth.json's
    parameters (nothing estimated, no covariance); "rms_delta_deg" is the RMS
    over a 41 x 41 grid of measured points spanning the whole 9 x 9 mm active
    area of |alpha_cal - alpha_true| (per-axis angles of arrival, model.md
    §5, §8.8). As a cross-check, the RMS angle between the estimated and the
    true rays on the same grid is recomputed in Python from the documented
    equations (experiments/realdata/psdcal_model.py). Reported per (lens,
    distortion): mean AoA RMS over seeds per fit, and the per-seed ratio
    default / min(explicit without l1, explicit with l1) (mean and max).
    Target: ratio <= 1.05. Also reported: the ratio to the explicit fit of the
    model that generated the data (k1,k2 without distortion, k1,k2,l1 with it)
    and the ratio of the means (mean default / min of the explicit means).

Run from the repository root (2 processes at a time by default):

    /usr/bin/python3 experiments/simulated/default_model.py \
        --psdcal target/release/psdcal --part a|b|all --json OUT.json

Options: --workdir DIR (simulated data and calibrations; default
/tmp/sim-exp/default_model), --seeds-a K, --seeds-b K, --jobs J.
"""

import argparse
import concurrent.futures as cf
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "realdata"))
import psdcal_model  # noqa: E402  (documented measured -> ray map, for the cross-check)

BASE = ["f", "cx", "cy", "k1", "k2"]
ZPARAMS = ["f", "cx", "cy"]
TRUTH_KEY = {"f": "f_mm", "cx": "cx_mm", "cy": "cy_mm"}
ALL_PARAMS = ["f", "cx", "cy", "skew", "k1", "k2", "k3", "p1", "p2", "l1", "l2"]


# ---------------------------------------------------------------- running psdcal

def run(cmd):
    """Run a command; return (exit code, the 'error:' line or stderr tail)."""
    p = subprocess.run(cmd, capture_output=True, text=True)
    msg = ""
    if p.returncode != 0:
        errs = [l for l in p.stderr.splitlines() if l.startswith("error:")]
        msg = errs[0] if errs else p.stderr.strip()[-300:]
    return p.returncode, msg, p.stdout


def simulate(psdcal, out, lens, images, seed, distortion):
    """`psdcal simulate` one data set into `out` (skipped when already there)."""
    if os.path.exists(os.path.join(out, "truth.json")):
        with open(os.path.join(out, "truth.json")) as f:
            s = json.load(f)["simulation"]
        if (s["lens"], s["images"], s["seed"], s["psd_distortion"]) == (lens, images, seed, distortion):
            return
    cmd = [psdcal, "-q", "simulate", "--lens", str(lens), "--snr", "40", "--images", str(images),
           "--seed", str(seed), "--out", out]
    if distortion:
        cmd.append("--psd-distortion")
    rc, msg, _ = run(cmd)
    if rc != 0:
        raise RuntimeError(f"simulate failed ({' '.join(cmd)}): {msg}")


def calibrate(psdcal, d, out, fit=None, uncertainty=None):
    """`psdcal calibrate` on data set d; returns (calibration dict or None, error message)."""
    cmd = [psdcal, "-q", "calibrate", "-t", os.path.join(d, "template.csv"),
           "-o", os.path.join(d, "observations.csv"), "--out", out]
    if fit:
        cmd += ["--fit", fit]
    if uncertainty:
        cmd += ["--uncertainty", uncertainty]
    if os.path.exists(out):
        os.remove(out)
    rc, msg, _ = run(cmd)
    if rc != 0:
        return None, f"exit {rc}: {msg}"
    with open(out) as f:
        return json.load(f), ""


def truth_calibration(d):
    """Write d/truth_cal.json: truth.json's model as a version-1 calibration.json
    with nothing estimated (so `psdcal diff` can compare a fit with the truth)."""
    with open(os.path.join(d, "truth.json")) as f:
        t = json.load(f)
    cal = {"format": "psdcal-calibration", "version": 1,
           "software": {"name": "psdcal", "version": "0.1.0"},
           "sensor": t["sensor"], "intrinsics": t["intrinsics"], "distortion": t["distortion"],
           "estimated": [], "fixed": ALL_PARAMS, "gains": None, "std": {},
           "covariance": {"parameters": [], "matrix": []},
           "fit": {"cost": "template", "noise": "uniform", "residual_mm2": 0.0,
                   "rms_template_mm": 0.0, "rms_image_mm": 0.0, "iterations": 0,
                   "points": 0, "images": 0, "termination": "truth (simulation)"},
           "images": []}
    path = os.path.join(d, "truth_cal.json")
    with open(path, "w") as f:
        json.dump(cal, f, indent=1)
    return path, t


def chosen_extra(cal):
    """The groups the default model choice added to f,cx,cy,k1,k2 (e.g. ['l1'])."""
    mc = cal.get("fit", {}).get("model_choice") or {}
    chosen = mc.get("chosen") or [n for s in cal["stages"] for n in s["estimated"]]
    return [n for n in chosen if n not in BASE]


def diagnostics(cal):
    return sorted({d["code"] for d in cal.get("diagnostics", []) if d.get("severity") != "info"})


# ---------------------------------------------------------------- Part A

def part_a_one(psdcal, workdir, lens, images, seed):
    d = os.path.join(workdir, f"a_l{lens}_n{images}_s{seed}")
    simulate(psdcal, d, lens, images, seed, False)
    with open(os.path.join(d, "truth.json")) as f:
        truth = json.load(f)["intrinsics"]
    rec = {"lens": lens, "images": images, "seed": seed}
    for method, unc in (("jackknife", None), ("linear", "linear")):
        cal, err = calibrate(psdcal, d, os.path.join(d, f"cal_{method}.json"), uncertainty=unc)
        if cal is None:
            rec[method] = {"failed": err}
            continue
        p, s = cal["parameters"], cal["std"]
        rec[method] = {
            "z": {k: (p[k] - truth[TRUTH_KEY[k]]) / s[k] for k in ZPARAMS},
            "est": {k: p[k] for k in ZPARAMS}, "std": {k: s[k] for k in ZPARAMS},
            "extra": chosen_extra(cal), "diagnostics": diagnostics(cal),
            "uncertainty": cal["fit"].get("uncertainty"),
        }
    return rec


def summarise_a(recs, method):
    """RMS z per parameter, fraction |z| <= 3, added groups and failures."""
    ok = [r[method] for r in recs if "z" in r[method]]
    fails = [(r["lens"], r["images"], r["seed"], r[method]["failed"]) for r in recs if "failed" in r[method]]
    out = {"runs": len(recs), "succeeded": len(ok), "failures": len(fails),
           "failure_messages": sorted({f[3] for f in fails}),
           "failed_runs": [list(f[:3]) for f in fails]}
    allz = []
    for k in ZPARAMS:
        z = np.array([o["z"][k] for o in ok])
        allz.append(z)
        out[f"rms_z_{k}"] = float(np.sqrt(np.mean(z ** 2))) if len(z) else None
        out[f"within3_{k}"] = float(np.mean(np.abs(z) <= 3)) if len(z) else None
        out[f"mean_z_{k}"] = float(np.mean(z)) if len(z) else None
    allz = np.concatenate(allz) if ok else np.array([])
    out["within3_all"] = float(np.mean(np.abs(allz) <= 3)) if len(allz) else None
    groups = {}
    for o in ok:
        key = ",".join(o["extra"]) or "(none)"
        groups[key] = groups.get(key, 0) + 1
    out["model_added"] = groups
    out["added_fraction"] = float(np.mean([bool(o["extra"]) for o in ok])) if ok else None
    diag = {}
    for o in ok:
        for c in o["diagnostics"]:
            diag[c] = diag.get(c, 0) + 1
    out["diagnostics"] = diag
    return out


def part_a(psdcal, workdir, seeds, jobs):
    t0 = time.time()
    tasks = [(lens, n, s) for lens in (1, 2) for n in (9, 12, 16, 20) for s in range(1, seeds + 1)]
    recs = []
    with cf.ThreadPoolExecutor(max_workers=jobs) as ex:
        futs = [ex.submit(part_a_one, psdcal, workdir, *t) for t in tasks]
        for i, fu in enumerate(cf.as_completed(futs), 1):
            recs.append(fu.result())
            if i % 50 == 0 or i == len(tasks):
                print(f"  part A: {i}/{len(tasks)} data sets, {time.time() - t0:.1f} s", flush=True)
    recs.sort(key=lambda r: (r["lens"], r["images"], r["seed"]))
    tables = {}
    for method in ("jackknife", "linear"):
        tab = {}
        for lens in (1, 2):
            tab[f"lens{lens}"] = summarise_a([r for r in recs if r["lens"] == lens], method)
            for n in (9, 12, 16, 20):
                tab[f"lens{lens}_N{n}"] = summarise_a(
                    [r for r in recs if r["lens"] == lens and r["images"] == n], method)
        tab["overall"] = summarise_a(recs, method)
        tables[method] = tab
    # do both methods pick the same model and the same estimate?
    same_model = sum(1 for r in recs if "z" in r["jackknife"] and "z" in r["linear"]
                     and r["jackknife"]["extra"] == r["linear"]["extra"])
    max_est_diff = max((abs(r["jackknife"]["est"][k] - r["linear"]["est"][k])
                        for r in recs if "z" in r["jackknife"] and "z" in r["linear"] for k in ZPARAMS),
                       default=None)
    # the largest |z| runs, to look at
    worst = sorted(((abs(r["jackknife"]["z"][k]), r["lens"], r["images"], r["seed"], k,
                     r["jackknife"]["z"][k], r["linear"]["z"][k] if "z" in r["linear"] else None,
                     r["jackknife"]["extra"])
                    for r in recs if "z" in r["jackknife"] for k in ZPARAMS), reverse=True)[:10]
    return {"tables": tables, "same_model_both_methods": same_model, "runs": len(recs),
            "max_abs_estimate_difference_between_methods": max_est_diff,
            "worst_z_default": [{"lens": w[1], "images": w[2], "seed": w[3], "param": w[4],
                                 "z_jackknife": w[5], "z_linear": w[6], "added": w[7]} for w in worst],
            "runs_detail": recs, "seconds": time.time() - t0}


def print_a(res):
    for method in ("jackknife", "linear"):
        print(f"\nPart A, uncertainty = {method} (default calibrate model choice)")
        print(f"{'group':<12}{'runs':>5}{'fail':>5}  {'RMS z f':>8}{'cx':>7}{'cy':>7}   "
              f"{'|z|<=3 f':>9}{'cx':>7}{'cy':>7}{'all':>7}   added")
        for key, s in res["tables"][method].items():
            if s["succeeded"] == 0:
                print(f"{key:<12}{s['runs']:>5}{s['failures']:>5}  (no successful runs)")
                continue
            print(f"{key:<12}{s['runs']:>5}{s['failures']:>5}  {s['rms_z_f']:>8.3f}{s['rms_z_cx']:>7.3f}"
                  f"{s['rms_z_cy']:>7.3f}   {s['within3_f']:>9.3f}{s['within3_cx']:>7.3f}"
                  f"{s['within3_cy']:>7.3f}{s['within3_all']:>7.3f}   {s['model_added']}")
        ov = res["tables"][method]["overall"]
        if ov["failure_messages"]:
            print("  failures:", ov["failure_messages"])
        print("  diagnostics (warnings) over all runs:", ov["diagnostics"])


# ---------------------------------------------------------------- Part B

FITS_B = {"default": None, "explicit": "f,cx,cy,k1,k2", "explicit_l1": "f,cx,cy,k1,k2,l1"}


def aoa_rms_diff(psdcal, truth_cal, cal_path):
    """psdcal's own measurement: `psdcal diff TRUTH CAL --json` -> (rms_delta_deg, answered, points)."""
    rc, msg, out = run([psdcal, "-q", "diff", truth_cal, cal_path, "--json"])
    if rc != 0:
        raise RuntimeError(f"diff failed: {msg}")
    j = json.loads(out)
    return j["rms_delta_deg"], j["answered"], j["points"], j["max_delta_deg"]


def aoa_rms_python(cal, truth):
    """Cross-check: RMS angle between estimated and true rays, 41 x 41 grid (psdcal_model.py)."""
    est = dict(cal["parameters"])
    est.setdefault("a", 0.0)
    tp = {"f": truth["intrinsics"]["f_mm"], "cx": truth["intrinsics"]["cx_mm"],
          "cy": truth["intrinsics"]["cy_mm"], "skew": truth["intrinsics"]["skew"], "a": 0.0,
          **truth["distortion"]}
    return psdcal_model.aoa_rms_deg(est, tp, half=truth["sensor"]["lx_mm"] / 2, n=41)


def part_b_one(psdcal, workdir, lens, distortion, seed):
    d = os.path.join(workdir, f"b_l{lens}_d{int(distortion)}_s{seed}")
    simulate(psdcal, d, lens, 12, seed, distortion)
    truth_cal, truth = truth_calibration(d)
    rec = {"lens": lens, "distortion": distortion, "seed": seed}
    for name, fit in FITS_B.items():
        path = os.path.join(d, f"cal_{name}.json")
        cal, err = calibrate(psdcal, d, path, fit=fit)
        if cal is None:
            rec[name] = {"failed": err}
            continue
        rms, answered, points, mx = aoa_rms_diff(psdcal, truth_cal, path)
        rec[name] = {"aoa_rms_deg": rms, "answered": answered, "points": points, "max_deg": mx,
                     "aoa_rms_ray_angle_deg_python": aoa_rms_python(cal, truth),
                     "extra": chosen_extra(cal), "diagnostics": diagnostics(cal),
                     "l1": cal["parameters"]["l1"]}
    ex = [rec[n]["aoa_rms_deg"] for n in ("explicit", "explicit_l1") if "aoa_rms_deg" in rec[n]]
    if "aoa_rms_deg" in rec["default"] and ex:
        rec["ratio"] = rec["default"]["aoa_rms_deg"] / min(ex)
    # the explicit fit of the model that generated the data (l1 only with --psd-distortion)
    right = "explicit_l1" if distortion else "explicit"
    if "aoa_rms_deg" in rec["default"] and "aoa_rms_deg" in rec[right]:
        rec["ratio_to_true_model"] = rec["default"]["aoa_rms_deg"] / rec[right]["aoa_rms_deg"]
    return rec


def summarise_b(recs):
    out = {"runs": len(recs)}
    for name in FITS_B:
        ok = [r[name] for r in recs if "aoa_rms_deg" in r[name]]
        out[f"failures_{name}"] = len(recs) - len(ok)
        out[f"mean_aoa_rms_deg_{name}"] = float(np.mean([o["aoa_rms_deg"] for o in ok])) if ok else None
        out[f"mean_aoa_rms_ray_deg_python_{name}"] = (
            float(np.mean([o["aoa_rms_ray_angle_deg_python"] for o in ok])) if ok else None)
        out[f"min_answered_{name}"] = min((o["answered"] for o in ok), default=None)
    ratios = [r["ratio"] for r in recs if "ratio" in r]
    out["ratio_mean"] = float(np.mean(ratios)) if ratios else None
    out["ratio_max"] = float(np.max(ratios)) if ratios else None
    out["ratio_max_seed"] = recs[int(np.argmax([r.get("ratio", -1) for r in recs]))]["seed"] if ratios else None
    out["ratio_over_1.05"] = int(sum(x > 1.05 for x in ratios))
    rt = [r["ratio_to_true_model"] for r in recs if "ratio_to_true_model" in r]
    out["ratio_to_true_model_mean"] = float(np.mean(rt)) if rt else None
    out["ratio_to_true_model_max"] = float(np.max(rt)) if rt else None
    means = [out[f"mean_aoa_rms_deg_{n}"] for n in ("explicit", "explicit_l1")
             if out[f"mean_aoa_rms_deg_{n}"] is not None]
    out["ratio_of_means"] = (out["mean_aoa_rms_deg_default"] / min(means)
                             if means and out["mean_aoa_rms_deg_default"] is not None else None)
    groups = {}
    for r in recs:
        if "extra" in r["default"]:
            key = ",".join(r["default"]["extra"]) or "(none)"
            groups[key] = groups.get(key, 0) + 1
    out["default_added"] = groups
    return out


def part_b(psdcal, workdir, seeds, jobs):
    t0 = time.time()
    tasks = [(lens, dist, s) for lens in (1, 2) for dist in (False, True) for s in range(1, seeds + 1)]
    recs = []
    with cf.ThreadPoolExecutor(max_workers=jobs) as ex:
        futs = [ex.submit(part_b_one, psdcal, workdir, *t) for t in tasks]
        for i, fu in enumerate(cf.as_completed(futs), 1):
            recs.append(fu.result())
            if i % 10 == 0 or i == len(tasks):
                print(f"  part B: {i}/{len(tasks)} data sets, {time.time() - t0:.1f} s", flush=True)
    recs.sort(key=lambda r: (r["lens"], r["distortion"], r["seed"]))
    tables = {}
    for lens in (1, 2):
        for dist in (False, True):
            tables[f"lens{lens}_{'psd_distortion' if dist else 'no_distortion'}"] = summarise_b(
                [r for r in recs if r["lens"] == lens and r["distortion"] == dist])
    tables["overall"] = summarise_b(recs)
    return {"tables": tables, "runs_detail": recs, "seconds": time.time() - t0}


def print_b(res):
    print("\nPart B: AoA RMS vs truth (psdcal diff, 41x41 grid over the active area), mean over seeds, degrees")
    print(f"{'condition':<28}{'default':>10}{'k1,k2':>10}{'k1,k2,l1':>10}   {'ratio mean':>10}{'max':>8}"
          f"{'>1.05':>6}{'vs true model mean':>20}{'max':>7}{'of means':>10}   default added")
    for key, s in res["tables"].items():
        f = lambda v: f"{v:>10.5f}" if v is not None else f"{'-':>10}"
        print(f"{key:<28}{f(s['mean_aoa_rms_deg_default'])}{f(s['mean_aoa_rms_deg_explicit'])}"
              f"{f(s['mean_aoa_rms_deg_explicit_l1'])}   {s['ratio_mean']:>10.3f}{s['ratio_max']:>8.3f}"
              f"{s['ratio_over_1.05']:>6}{s['ratio_to_true_model_mean']:>20.3f}"
              f"{s['ratio_to_true_model_max']:>7.3f}{s['ratio_of_means']:>10.3f}   {s['default_added']}")
    print("\nper seed (AoA RMS deg: default / k1,k2 / k1,k2,l1; ratio; default's added groups)")
    for r in res["runs_detail"]:
        g = lambda n: f"{r[n]['aoa_rms_deg']:.5f}" if "aoa_rms_deg" in r[n] else "FAIL"
        print(f"  lens {r['lens']} dist {int(r['distortion'])} seed {r['seed']:>2}: {g('default')} / "
              f"{g('explicit')} / {g('explicit_l1')}; ratio {r.get('ratio', float('nan')):.3f}; "
              f"{r['default'].get('extra')}")
        for n in FITS_B:
            if "failed" in r[n]:
                print(f"      {n} failed: {r[n]['failed']}")


# ---------------------------------------------------------------- main

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--psdcal", default="/tmp/psdcal-h30b")
    ap.add_argument("--part", choices=["a", "b", "all"], default="all")
    ap.add_argument("--json", help="write the tables (and every run) to this JSON file")
    ap.add_argument("--workdir", default="/tmp/sim-exp/default_model")
    ap.add_argument("--seeds-a", type=int, default=50)
    ap.add_argument("--seeds-b", type=int, default=10)
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    psdcal = os.path.abspath(a.psdcal)
    os.makedirs(a.workdir, exist_ok=True)
    result = {"psdcal": psdcal, "command": sys.argv}
    t0 = time.time()
    if a.part in ("a", "all"):
        print(f"Part A: 2 lenses x 4 image counts x {a.seeds_a} seeds", flush=True)
        result["part_a"] = part_a(psdcal, a.workdir, a.seeds_a, a.jobs)
        print_a(result["part_a"])
        print(f"Part A took {result['part_a']['seconds']:.1f} s")
    if a.part in ("b", "all"):
        print(f"\nPart B: 2 lenses x 2 distortion x {a.seeds_b} seeds", flush=True)
        result["part_b"] = part_b(psdcal, a.workdir, a.seeds_b, a.jobs)
        print_b(result["part_b"])
        print(f"Part B took {result['part_b']['seconds']:.1f} s")
    result["seconds"] = time.time() - t0
    if a.json:
        with open(a.json, "w") as f:
            json.dump(result, f, indent=1)
        print(f"wrote {a.json}")


if __name__ == "__main__":
    main()
