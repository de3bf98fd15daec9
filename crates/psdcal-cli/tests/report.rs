//! `psdcal report` and `psdcal study --report`: self-contained, escaped pages.

mod common;

use std::path::{Path, PathBuf};

use common::{psdcal, stderr, stdout};

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/example")
        .join(name)
}

/// The example data with hostile image labels and file names, calibrated.
fn hostile_data_set(dir: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let template = dir.join("tem<p>late&.csv");
    std::fs::copy(example("template.csv"), &template).unwrap();
    let text = std::fs::read_to_string(example("observations.csv")).unwrap();
    let mut out = String::new();
    for line in text.lines() {
        // The image column is the first one (checked below on the header).
        if line.starts_with("image,") || line.starts_with('#') || line.trim().is_empty() {
            out.push_str(line);
        } else {
            out.push_str("<i>img&'");
            out.push_str(line);
        }
        out.push('\n');
    }
    assert!(text.lines().any(|l| l.starts_with("image,led,")));
    let observations = dir.join("observations.csv");
    std::fs::write(&observations, out).unwrap();
    let calibration = dir.join("calibration.json");
    let run = psdcal([
        "-q".as_ref(),
        "calibrate".as_ref(),
        "-t".as_ref(),
        template.as_os_str(),
        "-o".as_ref(),
        observations.as_os_str(),
        "--out".as_ref(),
        calibration.as_os_str(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    (calibration, template, observations)
}

#[test]
fn report_is_self_contained_escaped_and_has_every_plot() {
    let dir = tempfile::tempdir().unwrap();
    let (calibration, template, observations) = hostile_data_set(dir.path());
    let out = dir.path().join("report");
    let run = psdcal([
        "--json".as_ref(),
        "report".as_ref(),
        "-c".as_ref(),
        calibration.as_os_str(),
        "-t".as_ref(),
        template.as_os_str(),
        "-o".as_ref(),
        observations.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let json: serde_json::Value = serde_json::from_str(&stdout(&run)).unwrap();
    let plots: Vec<&str> = json["plots"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_str().unwrap())
        .collect();
    for name in [
        "coverage",
        "residuals_template",
        "residuals_sensor",
        "distortion_field",
        "spiral",
        "aoa_sensitivity",
        "aoa_error_map",
        "position_error_map",
    ] {
        assert!(plots.contains(&name), "{name} in {plots:?}");
        assert!(out.join(format!("{name}.svg")).is_file());
        let png = std::fs::read(out.join(format!("{name}.png"))).unwrap();
        assert_eq!(&png[1..4], b"PNG");
    }
    assert_eq!(json["files"].as_array().unwrap().len(), 1 + 2 * plots.len());

    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert_eq!(html.matches("<svg").count(), plots.len());
    assert!(!html.contains("<?xml"));
    // Nothing active, nothing from the network.
    for bad in [
        "<script", "<link", "<img", "<iframe", "https://", "src=", "@import", "<i>img",
    ] {
        assert!(!html.to_ascii_lowercase().contains(bad), "{bad}");
    }
    // User text escaped: image labels (tables and SVG legends), file names.
    assert!(html.contains("&lt;i&gt;img&amp;&#39;"), "table label");
    assert!(html.contains("&lt;i&gt;img&amp;&apos;"), "svg legend label");
    assert!(html.contains("tem&lt;p&gt;late&amp;.csv"), "file name");
    assert!(html.contains("@media print") && html.contains("viewport"));
    for heading in ["Parameters", "Fit summary", "RMS template plane (mm)"] {
        assert!(html.contains(heading), "{heading}");
    }
    // No leftover temporary files (the folder's manifest of psdcal's
    // outputs, docs/formats.md "Outputs", is the one hidden file).
    assert!(std::fs::read_dir(&out).unwrap().all(|e| {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        !name.starts_with('.') || name == ".psdcal-outputs"
    }));
}

#[test]
fn report_without_data_quiet_and_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let calibration = dir.path().join("calibration.json");
    let run = psdcal([
        "-q".as_ref(),
        "calibrate".as_ref(),
        "-t".as_ref(),
        example("template.csv").as_os_str(),
        "-o".as_ref(),
        example("observations.csv").as_os_str(),
        "--out".as_ref(),
        calibration.as_os_str(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let run = psdcal([
        "-q".as_ref(),
        "report".as_ref(),
        "-c".as_ref(),
        calibration.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stdout(&run).is_empty());
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("Distortion correction") && !html.contains("Coverage of the sensor"));
    // --template needs --observations.
    let run = psdcal([
        "report".as_ref(),
        "-c".as_ref(),
        calibration.as_os_str(),
        "-t".as_ref(),
        example("template.csv").as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(run.status.code(), Some(2));
    // A missing calibration is one error line.
    let run = psdcal(["report", "-c", "missing.json", "--out", "x"]);
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).starts_with("error:"));
}

#[test]
fn study_report_page_has_tables_and_histograms() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("study");
    let page = dir.path().join("page");
    let run = psdcal([
        "-q".as_ref(),
        "study".as_ref(),
        "table1".as_ref(),
        "--trials".as_ref(),
        "3".as_ref(),
        "--threads".as_ref(),
        "1".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
        "--report".as_ref(),
        page.as_os_str(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stdout(&run).is_empty());
    let html = std::fs::read_to_string(page.join("study.html")).unwrap();
    assert!(html.contains("<table>") && html.contains("focal length f (mm)"));
    assert!(html.contains("Histograms"));
    // Issue 18: warnings and what was run first, the bias against the truth
    // and the paper's numbers beside psdcal's, numbers rounded by the spread.
    let at = |s: &str| html.find(s).unwrap_or_else(|| panic!("{s} missing"));
    assert!(at("<h2>Warnings</h2>") < at("<h2>What was run</h2>"));
    assert!(at("<h2>What was run</h2>") < at("<h2>Table 1 (lens 1)"));
    assert!(html.contains("Only 3 trials per condition"));
    assert!(html.contains("Command: psdcal study table1 --trials 3 --seed 1"));
    assert!(html.contains(concat!("psdcal version: ", env!("CARGO_PKG_VERSION"))));
    assert!(html.contains("Bias: mean − true value") && html.contains("style=\"background:"));
    assert!(html.contains("The paper&#39;s numbers") && html.contains(">26.215</td>"));
    assert!(html.contains(" ± "));
    assert!(html.matches("<svg").count() >= 3);
    assert!(!html.contains("<script"));
}
