//! `psdcal export` end to end: a simulated data set is calibrated, exported
//! to OpenCV, mrcal and ROS, and the exported models are read by the real
//! OpenCV, mrcal and PyYAML (Debian's `python3-opencv`, `python3-mrcal`,
//! `python3-yaml` for /usr/bin/python3; `.ci/run` installs them): the angles
//! they give every grid point of the valid region match psdcal's `aoa`
//! within 1e-3° (`tests/export_roundtrip.py`). Without those modules the
//! test fails, unless `PSDCAL_SKIP_PYTHON_EXPORT=1` says to skip it (with a
//! loud message). Also: ROS's plumb_bob when it is good enough, refusals
//! with their reason (a PSD map, a threshold below the error, a pitch that
//! does not divide the sensor), and the JSON summary.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{psdcal, stderr, stdout};
use serde_json::Value;

const PYTHON: &str = "/usr/bin/python3";

fn run_ok(args: &[&str]) -> String {
    let out = psdcal(args);
    assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
    stdout(&out)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A calibration of a simulated lens (`--lens`), in `dir`.
fn calibration(dir: &Path, lens: &str, extra: &[&str]) -> PathBuf {
    let sim = dir.join(format!("sim{lens}"));
    let mut args = vec![
        "simulate",
        "--lens",
        lens,
        "--snr",
        "40",
        "-q",
        "--out",
        s(&sim),
    ];
    args.extend(extra);
    run_ok(&args);
    let cal = dir.join(format!("cal{lens}.json"));
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

/// psdcal's angles on a 41 × 41 grid over the 9 mm active area.
fn aoa_grid(dir: &Path, cal: &Path) -> PathBuf {
    let mut text = String::from("x_mm,y_mm\n");
    for j in 0..41 {
        for i in 0..41 {
            let t = |k: i32| -4.5 + 9.0 * f64::from(k) / 40.0;
            text += &format!("{},{}\n", t(i), t(j));
        }
    }
    let points = dir.join("grid.csv");
    std::fs::write(&points, text).unwrap();
    let aoa = dir.join("aoa.csv");
    run_ok(&[
        "aoa",
        "-q",
        "-c",
        s(cal),
        "-p",
        s(&points),
        "--out",
        s(&aoa),
    ]);
    aoa
}

/// Whether Debian's Python has the readers; panics unless the skip is
/// requested.
fn python_ready() -> bool {
    let ok = Command::new(PYTHON)
        .args(["-c", "import cv2, mrcal, yaml, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if ok {
        return true;
    }
    let skip = std::env::var("PSDCAL_SKIP_PYTHON_EXPORT").is_ok_and(|v| v == "1");
    assert!(
        skip,
        "{PYTHON} lacks cv2, mrcal or yaml: install python3-opencv python3-mrcal python3-yaml \
         (apt-get), or set PSDCAL_SKIP_PYTHON_EXPORT=1 to skip this check"
    );
    eprintln!(
        "\n!!!!! SKIPPED: the exports were NOT checked with OpenCV and mrcal ({PYTHON} lacks \
         them; PSDCAL_SKIP_PYTHON_EXPORT=1) !!!!!\n"
    );
    false
}

/// Runs the round-trip script; its JSON lines.
fn round_trip(aoa: &Path, pitch: &str, tol: &str, files: &[(&str, &Path)]) -> Vec<Value> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/export_roundtrip.py");
    let mut cmd = Command::new(PYTHON);
    cmd.arg(&script).args([s(aoa), pitch, "9", "9", tol]);
    for (kind, path) in files {
        cmd.arg(format!("{kind}={}", s(path)));
    }
    let out = cmd.output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn exports_give_psdcal_angles_in_opencv_and_mrcal() {
    let dir = tempfile::tempdir().unwrap();
    let cal = calibration(dir.path(), "2", &[]);
    let mut files = Vec::new();
    for (to, pitch) in [("opencv", "1"), ("mrcal", "1"), ("ros", "1")] {
        let out = dir.path().join(format!("model.{to}"));
        let json: Value = serde_json::from_str(&run_ok(&[
            "export",
            "--json",
            "-c",
            s(&cal),
            "--to",
            to,
            "--pixel-um",
            pitch,
            "--out",
            s(&out),
        ]))
        .unwrap();
        assert_eq!(json["model"], "rational", "{json}");
        assert_eq!(json["image_px"], serde_json::json!([9000, 9000]));
        let max = json["error"]["max_deg"].as_f64().unwrap();
        assert!(max > 0.0 && max < 1e-3, "{json}");
        // Lens 2 is beyond plumb_bob (about 0.3°).
        if to == "ros" {
            assert!(json["plumb_bob_max_deg"].as_f64().unwrap() > 0.05, "{json}");
        }
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.contains("u = 1000 (x_mm + Lx/2)/1 - 0.5"), "{text}");
        assert!(text.contains("conversion error over the valid region"));
        files.push((to, out));
    }
    if !python_ready() {
        return;
    }
    let aoa = aoa_grid(dir.path(), &cal);
    let listed: Vec<(&str, &Path)> = files.iter().map(|(k, p)| (*k, p.as_path())).collect();
    let results = round_trip(&aoa, "1", "1e-3", &listed);
    assert_eq!(results.len(), 3);
    for r in &results {
        println!("{r}");
        assert!(r["points"].as_u64().unwrap() > 1500, "{r}");
        assert!(r["max_deg"].as_f64().unwrap() < 1e-3, "{r}");
    }
}

#[test]
fn ros_gets_plumb_bob_when_it_is_good_enough_at_another_pitch() {
    let dir = tempfile::tempdir().unwrap();
    let cal = calibration(dir.path(), "1", &[]);
    let out = dir.path().join("camera_info.yaml");
    let json: Value = serde_json::from_str(&run_ok(&[
        "export",
        "--json",
        "-c",
        s(&cal),
        "--to",
        "ros",
        "--pixel-um",
        "4.5",
        "--max-error-deg",
        "0.01",
        "--out",
        s(&out),
    ]))
    .unwrap();
    assert_eq!(json["model"], "plumb_bob", "{json}");
    assert_eq!(json["image_px"], serde_json::json!([2000, 2000]));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("distortion_model: plumb_bob") && text.contains("cols: 5"));
    let max = json["error"]["max_deg"].as_f64().unwrap();
    if !python_ready() {
        return;
    }
    let aoa = aoa_grid(dir.path(), &cal);
    let tol = format!("{}", max * 1.2);
    let results = round_trip(&aoa, "4.5", &tol, &[("ros", &out)]);
    assert_eq!(results[0]["model"], "plumb_bob");
}

#[test]
fn what_cannot_be_represented_is_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A calibration with a PSD map: a non-radial field.
    let (sim, _, map) = common::simulated_map(d, &["--model", "poly:5"]);
    let cal = d.join("cal.json");
    run_ok(&[
        "calibrate",
        "-q",
        "-t",
        s(&sim.join("template.csv")),
        "-o",
        s(&sim.join("observations.csv")),
        "--psd-map",
        s(&map),
        "--out",
        s(&cal),
    ]);
    let out = d.join("model.yaml");
    let refused = psdcal(["export", "-c", s(&cal), "--to", "opencv", "--out", s(&out)]);
    assert_eq!(refused.status.code(), Some(1));
    let err = stderr(&refused);
    assert!(
        err.contains("PSD map (poly:5)") && err.contains("--max-error-deg"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!out.exists());
    // Raising the threshold writes it, with the reason as a warning.
    let written = psdcal([
        "export",
        "-c",
        s(&cal),
        "--to",
        "mrcal",
        "--max-error-deg",
        "5",
        "--out",
        s(&out),
    ]);
    assert_eq!(written.status.code(), Some(0), "{}", stderr(&written));
    assert!(stderr(&written).contains("warning: its PSD map"));
    assert!(std::fs::read_to_string(&out)
        .unwrap()
        .contains("# warning: its PSD map"));
    // A threshold below the fit's error, a pitch that does not divide 9 mm,
    // an output that is the input.
    let plain = calibration(d, "2", &[]);
    for (args, expected) in [
        (
            vec!["--max-error-deg", "1e-9"],
            "beyond the 8-coefficient rational model",
        ),
        (vec!["--pixel-um", "0.7"], "not a whole number"),
        (vec!["--pixel-um", "0"], "expected a positive number"),
    ] {
        let mut all = vec!["export", "-c", s(&plain), "--to", "ros", "--out", s(&out)];
        all.extend(args);
        let o = psdcal(&all);
        assert_eq!(o.status.code(), Some(1), "{all:?}");
        assert!(stderr(&o).contains(expected), "{}", stderr(&o));
    }
    let o = psdcal(["export", "-c", s(&plain), "--to", "ros", "--out", s(&plain)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}
