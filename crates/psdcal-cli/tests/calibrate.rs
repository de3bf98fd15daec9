//! `psdcal calibrate` end to end on the shipped example data (the paper's
//! lens 2, nine noise-free poses), and its refusals.

mod common;

use std::path::PathBuf;

use common::{psdcal, stderr, stdout};
use psdcal_io::read_calibration;

fn example(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/example")
        .join(name)
        .display()
        .to_string()
}

#[test]
fn calibrates_the_example_and_the_result_is_usable() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("calibration.json");
    let residuals = dir.path().join("residuals.csv");
    let run = psdcal([
        "calibrate",
        "--template",
        &example("template.csv"),
        "--observations",
        &example("observations.csv"),
        "--out",
        out.to_str().unwrap(),
        "--residuals",
        residuals.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "stderr: {}", stderr(&run));
    let text = stdout(&run);
    assert!(text.contains("residual:") && text.contains("± "), "{text}");
    let cal = read_calibration(&out).unwrap();
    let model = cal.to_model();
    // Noise-free data: the truth (lens 2 of docs/model.md §7) to 1e-6.
    assert!(
        (model.intrinsics.f - 8.0).abs() < 8e-6,
        "f = {}",
        model.intrinsics.f
    );
    assert!((model.intrinsics.cx - 0.5).abs() < 1e-6);
    assert!((model.intrinsics.cy + 0.7).abs() < 1e-6);
    assert!((model.distortion.k1 - 1e-2).abs() < 1e-8);
    assert!(cal.fit.residual_mm2 < 1e-12);
    assert_eq!(cal.images.len(), 9);
    assert_eq!(cal.fit.points, 126);
    assert_eq!(cal.std.names(), vec!["f", "cx", "cy", "k1", "k2"]);
    // One residual row per point, plus the header.
    let rows = std::fs::read_to_string(&residuals).unwrap();
    assert_eq!(rows.lines().count(), 127);
    assert!(rows.starts_with("image,led,x_mm,y_mm,X_mm,Y_mm,template_dx_mm"));
    // The calibration feeds `correct`.
    let points = dir.path().join("points.csv");
    std::fs::write(&points, "x_mm,y_mm\n1.0,2.0\n").unwrap();
    let corrected = psdcal([
        "correct",
        "-c",
        out.to_str().unwrap(),
        "-p",
        points.to_str().unwrap(),
    ]);
    assert!(corrected.status.success(), "{}", stderr(&corrected));
    assert!(stdout(&corrected).starts_with("x_mm,y_mm,x_ideal_mm,y_ideal_mm"));
}

#[test]
fn json_report_and_every_lens_term() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.json");
    let run = psdcal([
        "--json",
        "calibrate",
        "-t",
        &example("template.csv"),
        "-o",
        &example("observations.csv"),
        "--fit",
        "f,cx,cy,skew,k1,k2,k3,p1,p2",
        "--cost",
        "image",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "stderr: {}", stderr(&run));
    let report: serde_json::Value = serde_json::from_str(&stdout(&run)).unwrap();
    assert_eq!(report["cost"], "image");
    let params = report["parameters"].as_array().unwrap();
    assert_eq!(params.len(), 11);
    let f = params.iter().find(|p| p["name"] == "f").unwrap();
    assert!((f["value"].as_f64().unwrap() - 8.0).abs() < 1e-5);
    assert_eq!(report["covariance_parameters"].as_array().unwrap().len(), 9);
    assert_eq!(report["correlation"].as_array().unwrap().len(), 9);
}

#[test]
fn refusals_exit_non_zero_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    // Two images only.
    let obs = std::fs::read_to_string(example("observations.csv")).unwrap();
    let two: String = obs
        .lines()
        .filter(|l| {
            l.starts_with('#')
                || l.starts_with("image")
                || l.starts_with("1,")
                || l.starts_with("2,")
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let path = dir.path().join("two.csv");
    std::fs::write(&path, two).unwrap();
    let out = dir.path().join("c.json");
    let run = psdcal([
        "calibrate",
        "-t",
        &example("template.csv"),
        "-o",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(1));
    let err = stderr(&run);
    assert!(err.contains("error:") && err.contains("image"), "{err}");
    assert!(!err.contains("panicked"));
    assert!(!out.exists(), "no calibration is written on failure");
    // Usage errors: exit 2.
    for args in [
        vec![
            "calibrate",
            "-t",
            "t",
            "-o",
            "o",
            "--out",
            "c",
            "--fit",
            "f,zz",
        ],
        vec![
            "calibrate",
            "-t",
            "t",
            "-o",
            "o",
            "--out",
            "c",
            "--fit",
            "f,cx,cy,l1",
            "--set",
            "l1=-1e-3",
        ],
        vec![
            "calibrate",
            "-t",
            "t",
            "-o",
            "o",
            "--out",
            "c",
            "--robust",
            "huber",
        ],
        vec![
            "calibrate",
            "-t",
            "t",
            "-o",
            "o",
            "--out",
            "c",
            "--focal-guess",
            "-8",
        ],
        vec!["calibrate", "-t", "t", "-o", "o"],
    ] {
        let run = psdcal(&args);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {}", stderr(&run));
    }
    // An output folder that does not exist is created (as simulate and
    // report create theirs); one that cannot be created is refused.
    let run = psdcal([
        "calibrate",
        "-t",
        &example("template.csv"),
        "-o",
        &example("observations.csv"),
        "--out",
        dir.path().join("missing/c.json").to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    assert!(dir.path().join("missing/c.json").is_file());
    std::fs::write(dir.path().join("a-file"), "").unwrap();
    let run = psdcal([
        "calibrate",
        "-t",
        &example("template.csv"),
        "-o",
        &example("observations.csv"),
        "--out",
        dir.path().join("a-file/c.json").to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("a-file"), "{}", stderr(&run));
}

/// `--noise channel-snr` takes each record's SNR from signals.csv's
/// `snr_db` (as `psdcal demodulate` writes it): one SNR for every record
/// changes nothing (the weights are relative), records of different SNR
/// change the fit.
#[test]
fn channel_snr_uses_each_records_snr() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = psdcal([
        "simulate",
        "--lens",
        "2",
        "--snr",
        "40",
        "--images",
        "9",
        "--seed",
        "5",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let signals = std::fs::read_to_string(d.join("signals.csv")).unwrap();
    let with_snr = |snr: &dyn Fn(&str) -> f64, name: &str| -> String {
        let mut text = String::new();
        for line in signals.lines() {
            if line.starts_with('#') {
                text.push_str(line);
            } else if line.starts_with("image,") {
                text.push_str(&format!("{line},snr_db"));
            } else {
                let image = line.split(',').next().unwrap();
                text.push_str(&format!("{line},{}", snr(image)));
            }
            text.push('\n');
        }
        let path = d.join(name);
        std::fs::write(&path, text).unwrap();
        path.display().to_string()
    };
    let t = d.join("template.csv").display().to_string();
    let fit = |signals: &str, tag: &str| -> Vec<f64> {
        let cal = d.join(format!("{tag}.json"));
        let out = psdcal([
            "calibrate",
            "-q",
            "-t",
            &t,
            "-s",
            signals,
            "--noise",
            "channel-snr",
            "--out",
            cal.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{tag}: {}", stderr(&out));
        let m = read_calibration(&cal).unwrap().to_model();
        let (i, d) = (m.intrinsics, m.distortion);
        vec![i.f, i.cx, i.cy, d.k1, d.k2]
    };
    let plain = fit(d.join("signals.csv").to_str().unwrap(), "plain");
    let same = fit(&with_snr(&|_| 40.0, "same.csv"), "same");
    let mixed = fit(
        &with_snr(
            &|image| {
                if image.ends_with(['1', '3', '5', '7', '9']) {
                    30.0
                } else {
                    50.0
                }
            },
            "mixed.csv",
        ),
        "mixed",
    );
    for (k, (a, b)) in plain.iter().zip(&same).enumerate() {
        assert!(
            (a - b).abs() <= 1e-9 * a.abs().max(1e-6),
            "parameter {k}: {a} vs {b}"
        );
    }
    let moved = plain
        .iter()
        .zip(&mixed)
        .map(|(a, b)| (a - b).abs() / a.abs().max(1e-6))
        .fold(0.0, f64::max);
    assert!(
        moved > 1e-6,
        "records of 30 and 50 dB weighed alike ({moved:e})"
    );
}
