//! The project's own noise-free example data (data/example) calibrate
//! without a warning: the fit is exact (the solver's exact-fit criterion,
//! mean squared residual per point ≤ 1e-20 mm²), so no uncertainty check
//! runs and none can fire on rounding noise; the diagnostics are empty.

mod common;

use std::path::PathBuf;

fn example(file: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/example")
        .join(file)
        .display()
        .to_string()
}

#[test]
fn the_example_data_calibrate_without_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    for points in ["--observations", "--signals"] {
        let file = if points == "--observations" {
            example("observations.csv")
        } else {
            example("signals.csv")
        };
        let out = dir.path().join("calibration.json");
        let run = common::psdcal([
            "calibrate",
            "--template",
            &example("template.csv"),
            points,
            &file,
            "--out",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{points}: {stderr}");
        assert!(!stderr.contains("warning"), "{points}: {stderr}");
        let record: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        assert_eq!(record["diagnostics"], serde_json::json!([]), "{points}");
        // f = 8 mm to rounding: the data are exact.
        let f = record["parameters"]["f"].as_f64().unwrap();
        assert!((f - 8.0).abs() < 1e-9, "{points}: f = {f}");
    }
}

/// A file past `--max-input-mb` is refused in one line that says once what
/// to do (the library's message states the fact, the command line's advice
/// the remedy).
#[test]
fn a_file_past_the_size_limit_is_refused_with_the_remedy_said_once() {
    let dir = tempfile::tempdir().unwrap();
    let big = dir.path().join("observations.csv");
    let mut text = String::from("image,led,x_mm,y_mm\n");
    while text.len() < 1_100_000 {
        text.push_str("1,1,0.125,-0.25\n");
    }
    std::fs::write(&big, text).unwrap();
    let run = common::psdcal([
        "--max-input-mb",
        "1",
        "check",
        "--template",
        &example("template.csv"),
        "--observations",
        big.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("the file is larger than 1 MiB, the largest file read whole"),
        "{stderr}"
    );
    assert_eq!(stderr.matches("--max-input-mb").count(), 1, "{stderr}");
}
