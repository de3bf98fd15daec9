//! calibration.json versions: a version 1 file and the version 2 file of
//! the same calibration give the same answers in every command that reads
//! calibrations; `calibrate` writes version 2 with its provenance.

mod common;

use std::path::PathBuf;

use common::{data_dir, psdcal, stderr, stdout, valid};
use serde_json::Value;

/// The version 1 fixture (the calibration of `valid/calibration.json`,
/// written by psdcal 0.1 before version 2 existed).
fn v1() -> PathBuf {
    data_dir("valid").join("calibration_v1.json")
}

/// Standard output of `psdcal ARGS` with the calibration `cal` after `-c`.
fn answer(cal: &PathBuf, args: &[&str]) -> String {
    let mut all: Vec<std::ffi::OsString> = vec![args[0].into(), "-c".into(), cal.into()];
    all.extend(args[1..].iter().map(|a| a.into()));
    let out = psdcal(&all);
    assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
    stdout(&out)
}

#[test]
fn the_fixtures_are_one_calibration_in_both_versions() {
    let read = |p: &PathBuf| -> Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    assert_eq!(read(&v1())["version"], 1);
    assert_eq!(read(&valid("calibration.json"))["version"], 2);
    let (a, b) = (
        psdcal_io::read_calibration(v1()).unwrap(),
        psdcal_io::read_calibration(valid("calibration.json")).unwrap(),
    );
    assert_eq!(a.to_model(), b.to_model());
    assert_eq!(a.gains(), b.gains());
    assert_eq!(a.covariance, b.covariance);
}

#[test]
fn every_command_answers_the_same_from_version_1_and_2() {
    let points = valid("points.csv");
    let amplitudes = valid("points_amplitudes.csv");
    let (p, a) = (points.to_str().unwrap(), amplitudes.to_str().unwrap());
    for args in [
        vec!["aoa", "-p", p, "--point-sigma", "0.001"],
        vec!["aoa", "-p", a],
        vec!["correct", "-p", p],
        vec!["correct", "-p", a],
        vec!["locate", "-p", p, "--distance", "5000"],
        vec!["locate", "-p", a, "--plane", "0,-1,0,2500"],
        vec!["map", "--k-sigma", "2", "--grid", "5"],
    ] {
        let one = answer(&v1(), &args);
        let two = answer(&valid("calibration.json"), &args);
        assert!(!one.is_empty(), "{args:?}");
        assert_eq!(one, two, "{args:?}");
    }
}

#[test]
fn calibrate_writes_version_2_with_provenance() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.json");
    let t = valid("template.csv");
    let o = valid("observations.csv");
    let run = psdcal([
        "-q".as_ref(),
        "calibrate".as_ref(),
        "-t".as_ref(),
        t.as_os_str(),
        "-o".as_ref(),
        o.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["version"], 2);
    let kinds: Vec<&str> = v["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["psd_radial", "lens", "pinhole"]);
    assert!((v["parameters"]["f"].as_f64().unwrap() - 8.0).abs() < 1e-6);
    assert_eq!(v["diagnostics"], serde_json::json!([]));
    let p = &v["provenance"];
    assert!(p["command"].as_str().unwrap().contains("calibrate"));
    assert_eq!(p["options"]["cost"], "template");
    assert_eq!(p["inputs"].as_array().unwrap().len(), 2);
    let bytes = std::fs::read(&t).unwrap();
    assert_eq!(p["inputs"][0]["sha256"], psdcal::sha256_hex(&bytes));
    assert!(p["created_utc"].as_str().unwrap().ends_with('Z'));
}
