//! Hostile data (issue 33): errors name the files they come from, and a
//! calibration too extreme to plot gives one clear line, not a plotting
//! library's message.

mod common;

use std::fs;

use common::{psdcal, stderr, valid};

#[test]
fn a_degenerate_data_set_names_its_files() {
    let dir = tempfile::tempdir().unwrap();
    // Every image the same pose: the data cannot determine the model.
    let text = fs::read_to_string(valid("observations.csv")).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap();
    let first: Vec<&str> = lines.filter_map(|l| l.strip_prefix("pose1")).collect();
    assert!(first.len() >= 4);
    let mut same = format!("{header}\n");
    for image in 1..=4 {
        for row in &first {
            same += &format!("pose{image}{row}\n");
        }
    }
    let o = dir.path().join("observations.csv");
    fs::write(&o, same).unwrap();
    let t = valid("template.csv");
    let out = psdcal([
        "calibrate",
        "-t",
        t.to_str().unwrap(),
        "-o",
        o.to_str().unwrap(),
        "--out",
        dir.path().join("c.json").to_str().unwrap(),
    ]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains(o.to_str().unwrap()), "{err}");
    assert!(!err.contains("no data rows"), "{err}");
}

#[test]
fn a_calibration_too_extreme_to_plot_is_one_clear_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = fs::read_to_string(valid("calibration.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["parameters"]["f"] = serde_json::json!(1e-300);
    for stage in json["stages"].as_array_mut().into_iter().flatten() {
        if stage["kind"] == "pinhole" {
            stage["parameters"]["f"] = serde_json::json!(1e-300);
        }
    }
    let c = dir.path().join("tiny_f.json");
    fs::write(&c, serde_json::to_string(&json).unwrap()).unwrap();
    let report = dir.path().join("report");
    let out = psdcal([
        "report",
        "-c",
        c.to_str().unwrap(),
        "--out",
        report.to_str().unwrap(),
    ]);
    let err = stderr(&out);
    assert!(
        !err.contains("panicked") && !err.contains("cannot plot"),
        "{err}"
    );
    if !out.status.success() {
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(c.to_str().unwrap()), "{err}");
    }
}
