//! `psdcal demo`, `simulate` and `study` end to end, and their refusals.

mod common;

use common::{psdcal, stderr, stdout};
use psdcal_io::{read_calibration, read_truth};

#[test]
fn demo_runs_and_reports_against_the_truth() {
    let run = psdcal(["demo"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let text = stdout(&run);
    assert!(text.contains("angle-of-arrival error"), "{text}");
    assert!(text.contains("error/std"));
    let json = psdcal(["--json", "demo"]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&json)).unwrap();
    // 40 dB: the focal length within 4σ of the truth, the AoA error below a degree.
    let f = v["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "f")
        .unwrap();
    let (truth, est, sd) = (
        f["truth"].as_f64().unwrap(),
        f["estimate"].as_f64().unwrap(),
        f["std"].as_f64().unwrap(),
    );
    assert!((est - truth).abs() < 4.0 * sd, "f {est} ± {sd} vs {truth}");
    assert!(v["aoa_rms_error_deg"].as_f64().unwrap() < 1.0);
}

#[test]
fn simulated_files_calibrate_back_to_their_truth() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sim");
    let run = psdcal([
        "simulate",
        "--lens",
        "1",
        "--snr",
        "50",
        "--images",
        "12",
        "--template",
        "grid",
        "--seed",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    for f in [
        "template.csv",
        "observations.csv",
        "signals.csv",
        "truth.json",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let truth = read_truth(out.join("truth.json")).unwrap();
    assert_eq!(truth.images.len(), 12);
    assert_eq!(truth.simulation.snr_db, Some(50.0));
    let cal_path = out.join("cal.json");
    let path = |f: &str| out.join(f).display().to_string();
    for input in ["--observations", "--signals"] {
        let file = if input == "--observations" {
            path("observations.csv")
        } else {
            path("signals.csv")
        };
        let run = psdcal([
            "calibrate",
            "-t",
            &path("template.csv"),
            input,
            &file,
            "--out",
            cal_path.to_str().unwrap(),
        ]);
        assert!(run.status.success(), "{}", stderr(&run));
        let cal = read_calibration(&cal_path).unwrap();
        let sd = cal.std.get("f").unwrap();
        assert!(
            (cal.intrinsics.f_mm - truth.intrinsics.f_mm).abs() < 5.0 * sd,
            "{input}: f {} ± {sd}",
            cal.intrinsics.f_mm
        );
        let sd = cal.std.get("cx").unwrap();
        assert!((cal.intrinsics.cx_mm - truth.intrinsics.cx_mm).abs() < 5.0 * sd);
    }
    // The same seed writes the same bytes.
    let again = dir.path().join("again");
    assert!(psdcal([
        "simulate",
        "--lens",
        "1",
        "--snr",
        "50",
        "--images",
        "12",
        "--template",
        "grid",
        "--seed",
        "3",
        "--out",
        again.to_str().unwrap(),
    ])
    .status
    .success());
    assert_eq!(
        std::fs::read(out.join("observations.csv")).unwrap(),
        std::fs::read(again.join("observations.csv")).unwrap()
    );
}

#[test]
fn study_is_identical_whatever_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let mut csv = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("t{threads}"));
        let run = psdcal([
            "-q",
            "study",
            "table2",
            "table6",
            "--trials",
            "3",
            "--threads",
            threads,
            "--seed",
            "5",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(run.status.success(), "{}", stderr(&run));
        for f in ["study.md", "study.csv", "study.json"] {
            assert!(out.join(f).exists());
        }
        csv.push(std::fs::read_to_string(out.join("study.csv")).unwrap());
    }
    assert_eq!(csv[0], csv[1]);
    assert!(csv[0].starts_with("table,condition,quantity"));
    // Two tables: 4 first-stage columns × 3 rows + 5 columns (3 of the paper,
    // 2 with self-calibrated gains) × 8 rows.
    assert_eq!(csv[0].lines().count(), 1 + 4 * 3 + 5 * 8);
}

#[test]
fn bad_options_are_refused_before_any_work() {
    for args in [
        vec!["study", "table11"],
        vec!["study", "--trials", "0"],
        vec!["study", "--threads", "0"],
        vec!["simulate", "--images", "2", "--out", "x"],
        vec!["simulate", "--snr", "abc", "--out", "x"],
        vec!["simulate", "--lens", "3", "--out", "x"],
        vec!["simulate", "--template", "ring", "--out", "x"],
    ] {
        let run = psdcal(&args);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {}", stderr(&run));
        assert!(
            stderr(&run).contains("expected") || stderr(&run).contains("unknown"),
            "{args:?}: {}",
            stderr(&run)
        );
    }
    // An output folder that cannot be written: refused at once, nothing left behind.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, "").unwrap();
    let blocked = file.join("study");
    let run = psdcal([
        "study",
        "table1",
        "--trials",
        "1",
        "--out",
        blocked.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(stderr(&run).contains("output folder"), "{}", stderr(&run));
}

#[test]
fn an_interrupted_study_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("study");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_psdcal"))
        .args([
            "study",
            "all",
            "--trials",
            "200",
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Let it start (the folder is checked and created first), then Ctrl-C.
    let started = std::time::Instant::now();
    while !out.exists() && started.elapsed().as_secs() < 10 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    let status = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let output = child.wait_with_output().unwrap();
    assert_eq!(
        output.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(String::from_utf8_lossy(&output.stderr).contains("interrupted"));
    let left: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "files left behind: {left:?}");
}

/// RMS image-plane error of a calibration of `simulate --record-cycles
/// cycles` (lens 2, 40 dB, seed 4).
fn rms_sensor_error(dir: &std::path::Path, cycles: &str) -> f64 {
    let sim = dir.join(format!("sim{cycles}"));
    let run = psdcal([
        "-q",
        "simulate",
        "--snr",
        "40",
        "--seed",
        "4",
        "--record-cycles",
        cycles,
        "--out",
        sim.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let run = psdcal([
        "--json",
        "calibrate",
        "-t",
        sim.join("template.csv").to_str().unwrap(),
        "-o",
        sim.join("observations.csv").to_str().unwrap(),
        "--out",
        sim.join("c.json").to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let v: serde_json::Value = serde_json::from_str(&stdout(&run)).unwrap();
    v["statistics"]["rms_image_mm"].as_f64().unwrap()
}

#[test]
fn longer_records_average_the_noise_down() {
    // The demodulated amplitude's variance falls as 1/M with the M samples
    // averaged: 625 − 25 cycles against 65 − 25 is 15× the samples, so the
    // point noise (and the RMS error) falls by √15 ≈ 3.9. One data set's RMS
    // over 126 points scatters by ~7 %: [3.0, 5.0] holds it with room.
    let dir = tempfile::tempdir().unwrap();
    let short = rms_sensor_error(dir.path(), "65");
    let long = rms_sensor_error(dir.path(), "625");
    let ratio = short / long;
    assert!(
        (3.0..=5.0).contains(&ratio),
        "RMS {short:e} vs {long:e}: ratio {ratio}"
    );
    let run = psdcal(["simulate", "--record-cycles", "25", "--out", "x"]);
    assert!(!run.status.success());
    assert!(
        stderr(&run).contains("more than the 25-cycle filter transient"),
        "{}",
        stderr(&run)
    );
}

/// `psdcal study psdmap`: the PSD map's condition (EXPERIMENTS.md) from
/// the command line, its section in study.md and its numbers in study.json
/// equal to the facade's experiment run here for the same seed.
#[test]
fn study_runs_the_psd_map_condition() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("study");
    let run = psdcal([
        "-q",
        "study",
        "psdmap",
        "--trials",
        "1",
        "--seed",
        "5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let md = std::fs::read_to_string(out.join("study.md")).unwrap();
    assert!(md.contains("non-radial non-linearity"), "{md}");
    assert!(
        !out.join(".psdmap-work").exists(),
        "the work folder is removed"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("study.json")).unwrap()).unwrap();
    let seed = &json["psd_map"]["seeds"][0];
    let again = ::psdcal::psd_map_seed(5, false).unwrap();
    assert_eq!(seed["map"].as_f64().unwrap(), again.map);
    assert_eq!(seed["l1"].as_f64().unwrap(), again.l1);
    assert_eq!(seed["clean"].as_f64().unwrap(), again.clean);
    // The condition's claim on this seed: the map beats freeing l1.
    assert!(again.map < again.l1, "{again:?}");
}
