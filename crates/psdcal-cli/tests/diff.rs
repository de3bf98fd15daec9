//! `psdcal diff` end to end: a calibration against itself is exactly zero;
//! two calibrations of simulated data sets (two seeds) against an
//! independent computation from two `aoa` runs over the same grid — the
//! maximum within 5 %, every point's difference, combined σ and |Δ|/σ from
//! the `aoa` columns (σ, ρ of each calibration); the heat-map page.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use common::{psdcal, stderr, stdout};
use serde_json::Value;

fn run_ok(args: &[&str]) -> String {
    let out = psdcal(args);
    assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
    stdout(&out)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn calibration(dir: &Path, seed: &str) -> PathBuf {
    let sim = dir.join(format!("sim{seed}"));
    run_ok(&[
        "simulate",
        "--lens",
        "2",
        "--snr",
        "40",
        "--seed",
        seed,
        "-q",
        "--out",
        s(&sim),
    ]);
    let cal = dir.join(format!("cal{seed}.json"));
    run_ok(&[
        "calibrate",
        "-q",
        "-t",
        s(&sim.join("template.csv")),
        "-o",
        s(&sim.join("observations.csv")),
        "--out",
        s(&cal),
    ]);
    cal
}

/// Rows of a CSV as maps from column to text.
fn rows(path: &Path) -> Vec<HashMap<String, String>> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_path(path)
        .unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    reader
        .records()
        .map(|r| {
            header
                .iter()
                .cloned()
                .zip(r.unwrap().iter().map(String::from))
                .collect()
        })
        .collect()
}

fn f(row: &HashMap<String, String>, name: &str) -> f64 {
    row[name]
        .parse()
        .unwrap_or_else(|_| panic!("{name}: {:?}", row[name]))
}

#[test]
fn a_calibration_against_itself_is_zero() {
    let dir = tempfile::tempdir().unwrap();
    let cal = calibration(dir.path(), "1");
    let map = dir.path().join("map.csv");
    let json: Value = serde_json::from_str(&run_ok(&[
        "diff",
        "--json",
        s(&cal),
        s(&cal),
        "--out",
        s(&map),
    ]))
    .unwrap();
    assert_eq!(json["max_delta_deg"].as_f64(), Some(0.0), "{json}");
    assert_eq!(json["rms_delta_deg"].as_f64(), Some(0.0));
    assert_eq!(json["max_z"].as_f64(), Some(0.0));
    assert_eq!(json["significant"], false);
    let rows = rows(&map);
    assert_eq!(rows.len(), 41 * 41);
    assert!(rows
        .iter()
        .all(|r| f(r, "delta_deg") == 0.0 && r["status"] == "ok"));
}

#[test]
fn two_seeds_match_two_independent_aoa_runs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (a, b) = (calibration(d, "1"), calibration(d, "2"));
    let map = d.join("map.csv");
    let report = d.join("report");
    let json: Value = serde_json::from_str(&run_ok(&[
        "diff",
        "--json",
        s(&a),
        s(&b),
        "--out",
        s(&map),
        "--report",
        s(&report),
    ]))
    .unwrap();
    // The same grid, written independently, through `aoa` with each.
    let mut text = String::from("x_mm,y_mm\n");
    for j in 0..41 {
        for i in 0..41 {
            let t = |k: i32| -4.5 + 9.0 * f64::from(k) / 40.0;
            text += &format!("{},{}\n", t(i), t(j));
        }
    }
    let points = d.join("grid.csv");
    std::fs::write(&points, text).unwrap();
    let answer = |cal: &Path, name: &str| {
        let out = d.join(name);
        run_ok(&[
            "aoa",
            "-q",
            "-c",
            s(cal),
            "-p",
            s(&points),
            "--out",
            s(&out),
        ]);
        rows(&out)
    };
    let (ra, rb) = (answer(&a, "a.csv"), answer(&b, "b.csv"));
    let map_rows = rows(&map);
    assert_eq!((ra.len(), rb.len(), map_rows.len()), (1681, 1681, 1681));
    let mut max: f64 = 0.0;
    for ((pa, pb), m) in ra.iter().zip(&rb).zip(&map_rows) {
        assert_eq!((pa["status"].as_str(), pb["status"].as_str()), ("ok", "ok"));
        let dx = f(pb, "alpha_x_deg") - f(pa, "alpha_x_deg");
        let dy = f(pb, "alpha_y_deg") - f(pa, "alpha_y_deg");
        let delta = dx.hypot(dy);
        max = max.max(delta);
        assert!((f(m, "delta_deg") - delta).abs() < 1e-9, "{m:?}");
        // Σ = Σ_A + Σ_B from each calibration's σ and ρ; σ along Δ; z.
        let cov = |r: &HashMap<String, String>| {
            let (sx, sy) = (f(r, "sigma_alpha_x_cal_deg"), f(r, "sigma_alpha_y_cal_deg"));
            let rho = f(r, "rho_alpha_xy");
            [sx * sx, rho * sx * sy, sy * sy]
        };
        let (ca, cb) = (cov(pa), cov(pb));
        let c = [ca[0] + cb[0], ca[1] + cb[1], ca[2] + cb[2]];
        assert!((f(m, "sigma_x_deg") - c[0].sqrt()).abs() < 1e-9 * c[0].sqrt().max(1.0));
        let (ux, uy) = (dx / delta, dy / delta);
        let sigma = (ux * ux * c[0] + 2.0 * ux * uy * c[1] + uy * uy * c[2]).sqrt();
        assert!(
            (f(m, "z") / (delta / sigma) - 1.0).abs() < 1e-6,
            "{m:?} vs {}",
            delta / sigma
        );
    }
    let reported = json["max_delta_deg"].as_f64().unwrap();
    assert!(max > 0.01, "the seeds differ: {max}");
    assert!((reported / max - 1.0).abs() < 0.05, "{reported} vs {max}");
    assert!(json["max_z"].as_f64().unwrap() > 0.0);
    let page = std::fs::read_to_string(report.join("diff.html")).unwrap();
    assert!(page.contains("<svg") && page.contains("Significance"));
    assert!(report.join("delta_map.svg").exists() && report.join("z_map.svg").exists());
    // The text summary names both files and the verdict.
    let text = run_ok(&["diff", s(&a), s(&b)]);
    assert!(
        text.contains("AoA difference: max") && text.contains("|Δ|/σ"),
        "{text}"
    );
    // An output over an input is refused before any work.
    let o = psdcal(["diff", s(&a), s(&b), "--out", s(&a)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}
