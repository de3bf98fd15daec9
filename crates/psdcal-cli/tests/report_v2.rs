//! The calibration report reads as a page for people (issue 18): numbers
//! rounded by their σ with units, no internal names, diagnostics first,
//! provenance with the inputs' SHA-256, the correlation matrix, the worst
//! points, a residual histogram, and residual arrows that stay readable at
//! many images (per-cell means).

mod common;

use std::fs;
use std::path::Path;

use common::{psdcal, stderr};

fn report(dir: &Path, images: &str) -> String {
    let sim = dir.join("sim");
    let s = sim.to_str().unwrap();
    let run = psdcal([
        "-q", "simulate", "--lens", "2", "--snr", "40", "--images", images, "--out", s,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let (t, o, c) = (
        format!("{s}/template.csv"),
        format!("{s}/observations.csv"),
        format!("{s}/calibration.json"),
    );
    let run = psdcal(["-q", "calibrate", "-t", &t, "-o", &o, "--out", &c]);
    assert!(run.status.success(), "{}", stderr(&run));
    let out = dir.join("report");
    let run = psdcal([
        "-q",
        "report",
        "-c",
        &c,
        "-t",
        &t,
        "-o",
        &o,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    fs::read_to_string(out.join("report.html")).unwrap()
}

#[test]
fn the_page_reads_as_a_report_for_people() {
    let dir = tempfile::tempdir().unwrap();
    let html = report(dir.path(), "9");
    // Diagnostics come before the parameters.
    let diag = html.find("<h2>Diagnostics</h2>").unwrap();
    assert!(diag < html.find("<h2>Parameters</h2>").unwrap());
    // Numbers rounded by σ with units; no internal names, no 7.958429e0.
    assert!(html.contains(" ± "), "value ± σ");
    assert!(html.contains("mm⁻²"), "units");
    for internal in [
        "Template<",
        ">Template",
        "CostConverged",
        "StepConverged",
        "e0<",
        "e-3<",
    ] {
        assert!(!html.contains(internal), "{internal}");
    }
    assert!(html.contains("focal length f"));
    // Provenance with the inputs' hashes.
    let obs = fs::read(dir.path().join("sim/observations.csv")).unwrap();
    // (psdcal's SHA-256 is checked against the standard's test vector in its own tests.)
    let sha = psdcal::sha256_hex(&obs);
    assert!(html.contains(&format!("SHA-256 {sha}")), "provenance");
    // Correlation matrix: a coloured cell per pair of the 5 parameters.
    assert!(html.contains("class=\"correlation\""));
    assert_eq!(html.matches("<td style=\"background:").count(), 25);
    // Worst points and the residual histogram.
    assert!(html.contains("<h2>Worst points</h2>"));
    assert!(html.contains("Sensor residuals"));
    assert!(html.contains("RMS residual per image"));
    assert!(dir.path().join("report/image_rms.svg").is_file());
    for bad in ["<script", "<link", "<img", "url(", "https://"] {
        assert!(!html.contains(bad), "{bad}");
    }
}

#[test]
fn residual_arrows_at_many_images_are_per_cell_means() {
    let dir = tempfile::tempdir().unwrap();
    report(dir.path(), "40");
    let svg = fs::read_to_string(dir.path().join("report/residuals_sensor.svg")).unwrap();
    // 40 images × 14 points = 560 residuals; at most 10 × 10 cells remain.
    let heads = svg.matches("<polygon").count();
    assert!(heads > 10 && heads <= 100, "{heads} arrow heads");
}
