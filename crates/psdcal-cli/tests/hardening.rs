//! Issue 17's reproducers, each run again: outputs over inputs (the report's page and
//! a rig's calibrations too), hostile values, outlier gains records, per-row
//! statuses, huge numbers, a mistyped LED named.

mod common;

use std::fs;

use common::{psdcal, stderr, stdout, valid};

/// Copies a fixture into `dir` and returns its path as text.
fn copy(dir: &std::path::Path, name: &str) -> String {
    let to = dir.join(name);
    fs::copy(valid(name), &to).unwrap();
    to.display().to_string()
}

#[test]
fn an_output_that_is_an_input_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let t = copy(dir.path(), "template.csv");
    let o = copy(dir.path(), "observations.csv");
    let c = copy(dir.path(), "calibration.json");
    let p = copy(dir.path(), "points.csv");
    let link = dir.path().join("link.csv");
    std::os::unix::fs::symlink(&o, &link).unwrap();
    let link = link.display().to_string();
    let other = dir.path().join("cal.json").display().to_string();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["calibrate", "-t", &t, "-o", &o, "--out", &o],
            o.as_str(),
        ),
        (
            vec!["calibrate", "-t", &t, "-o", &o, "--out", &t],
            t.as_str(),
        ),
        (
            vec!["calibrate", "-t", &t, "-o", &o, "--out", &link],
            o.as_str(),
        ),
        (
            vec![
                "calibrate",
                "-t",
                &t,
                "-o",
                &o,
                "--out",
                &other,
                "--residuals",
                &other,
            ],
            o.as_str(),
        ),
        (vec!["aoa", "-c", &c, "-p", &p, "--out", &p], p.as_str()),
        (vec!["aoa", "-c", &c, "-p", &p, "--out", &c], c.as_str()),
        (vec!["correct", "-c", &c, "-p", &p, "--out", &p], p.as_str()),
        (
            vec![
                "locate",
                "-c",
                &c,
                "-p",
                &p,
                "--distance",
                "1000",
                "--out",
                &c,
            ],
            c.as_str(),
        ),
    ];
    for (args, kept) in cases {
        let before = fs::read(kept).unwrap();
        let out = psdcal(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        let err = stderr(&out);
        assert!(err.starts_with("error: "), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.contains("overwrite") || err.contains("same file"),
            "{err}"
        );
        assert_eq!(fs::read(kept).unwrap(), before, "{args:?} changed {kept}");
    }
    assert!(!std::path::Path::new(&other).exists());
}

#[test]
fn values_that_overflow_are_usage_errors_or_failures() {
    let c = valid("calibration.json").display().to_string();
    let t = valid("template.csv").display().to_string();
    let o = valid("observations.csv").display().to_string();
    for args in [
        vec![
            "map",
            "--lens",
            "2",
            "--error",
            "f=0.05",
            "--distance",
            "1e308",
        ],
        vec!["map", "-c", &c, "--k-sigma", "1e308"],
        vec![
            "calibrate",
            "-t",
            &t,
            "-o",
            &o,
            "--out",
            "x.json",
            "--lx",
            "1e308",
        ],
    ] {
        let out = psdcal(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(!stdout(&out).contains("inf"), "{args:?}");
    }
    // Every grid point fails: an error, not a table of empty rows.
    let out = psdcal(["map", "--lens", "2", "--error", "f=-100"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("no grid point can be mapped"),
        "{}",
        stderr(&out)
    );
    assert!(stdout(&out).is_empty());
}

#[test]
fn an_implausible_focal_length_in_a_calibration_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = fs::read_to_string(valid("calibration.json")).unwrap();
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    let f = value["parameters"]["f"]
        .as_f64()
        .or(value["intrinsics"]["f_mm"].as_f64());
    assert!(f.is_some(), "the fixture has a focal length");
    let f_text = serde_json::to_string(&f.unwrap()).unwrap();
    let bad = text.replacen(&f_text, "1e308", usize::MAX);
    assert_ne!(bad, text);
    let path = dir.path().join("cal.json");
    fs::write(&path, bad).unwrap();
    let p = valid("points.csv").display().to_string();
    let out = psdcal(["aoa", "-c", path.to_str().unwrap(), "-p", &p]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("cal.json"), "{err}");
    assert!(err.contains("1e308"), "{err}");
    assert!(err.len() < 400, "{err}");
}

#[test]
fn gains_refuses_an_outlier_record_naming_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let records = dir.path().join("equal.csv");
    fs::write(
        &records,
        "vx1,vx2,vy1,vy2\n1,1.02,0.98,1.01\n1e-300,1,1,1\n1,1.03,0.97,1.0\n",
    )
    .unwrap();
    let out_file = dir.path().join("gains.json");
    let out = psdcal([
        "gains",
        "-s",
        records.to_str().unwrap(),
        "--out",
        out_file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("equal.csv:3:"), "{err}");
    assert!(err.contains("outlier"), "{err}");
    assert!(!err.contains("focal-guess"), "{err}");
    assert!(!out_file.exists());
}

#[test]
fn empty_and_non_finite_cells_are_rows_with_a_status() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("p.csv");
    fs::write(
        &points,
        "id,x_mm,y_mm\na,0.5,0.25\nb,,1\nc,nan,1\nd,1,1e999\ne,-0.5,0\n",
    )
    .unwrap();
    let amplitudes = dir.path().join("a.csv");
    fs::write(&amplitudes, "vx1,vx2,vy1,vy2\n1,1,1,1\n0,0,0,0\n1,,1,1\n").unwrap();
    let c0 = valid("calibration.json").display().to_string();
    for command in ["aoa", "correct"] {
        let out = psdcal([command, "-c", &c0, "-p", amplitudes.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{command}: {}", stderr(&out));
        let statuses: Vec<String> = stdout(&out)
            .lines()
            .skip(1)
            .map(|l| l.rsplit(',').next().unwrap().to_string())
            .collect();
        assert_eq!(
            statuses,
            ["ok", "no_light", "non_finite_input"],
            "{command}"
        );
    }
    let c = valid("calibration.json").display().to_string();
    for command in ["aoa", "correct"] {
        let out = psdcal([command, "-c", &c, "-p", points.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{command}: {}", stderr(&out));
        let text = stdout(&out);
        // (Zero amplitudes were once an error of `correct`: now a row `no_light`.)
        let statuses: Vec<&str> = text
            .lines()
            .skip(1)
            .map(|l| l.rsplit(',').next().unwrap())
            .collect();
        assert_eq!(
            statuses,
            [
                "ok",
                "non_finite_input",
                "non_finite_input",
                "non_finite_input",
                "ok"
            ],
            "{command}: {text}"
        );
        for line in text.lines().skip(1) {
            for field in line.split(',').skip(3) {
                assert!(
                    field.is_empty()
                        || field.parse::<f64>().is_ok_and(f64::is_finite)
                        || field.chars().all(|c| c.is_ascii_lowercase() || c == '_'),
                    "{line}"
                );
            }
        }
        assert!(
            stderr(&out).contains("p.csv:3: column 'x_mm' (2)"),
            "{}",
            stderr(&out)
        );
    }
}

#[test]
fn a_cr_only_file_gives_a_short_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("cr.csv");
    let mut bytes = b"x_mm,y_mm\r".to_vec();
    bytes.extend(b"0.5,0.25\r".repeat(200_000));
    fs::write(&points, bytes).unwrap();
    let c = valid("calibration.json").display().to_string();
    let out = psdcal(["aoa", "-c", &c, "-p", points.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(err.contains("cr.csv:1:"), "{err}");
    assert!(err.contains("carriage return alone"), "{err}");
    assert!(err.len() < 400, "{} bytes", err.len());
}

#[test]
fn a_syntax_error_in_a_rig_file_points_to_that_file() {
    let dir = tempfile::tempdir().unwrap();
    let rig = dir.path().join("rig.json");
    fs::write(&rig, "{\"format\": \"psdcal-rig\",\n  \"version\": 1,,}").unwrap();
    let p = valid("points.csv").display().to_string();
    let out = psdcal(["locate", "--rig", rig.to_str().unwrap(), "-p", &p]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(err.contains("rig.json:2:"), "{err}");
    assert!(!err.contains("calibration file"), "{err}");
}

#[test]
fn report_and_rig_outputs_that_are_inputs_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    // A calibration named like the report's page, in the report's folder.
    let page = dir.path().join("report.html");
    fs::copy(valid("calibration.json"), &page).unwrap();
    let before = fs::read(&page).unwrap();
    let out = psdcal([
        "report",
        "-c",
        page.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("overwrite"), "{}", stderr(&out));
    assert_eq!(fs::read(&page).unwrap(), before);
    // `locate --rig` writing over a calibration the rig lists.
    let a = copy(dir.path(), "calibration.json");
    let b = dir.path().join("b.json");
    fs::copy(valid("calibration.json"), &b).unwrap();
    let rig = dir.path().join("rig.json");
    fs::write(
        &rig,
        r#"{"format": "psdcal-rig", "version": 1, "sensors": [
  {"id": "a", "calibration": "calibration.json",
   "world_from_sensor": {"rvec": [0, 0, 0], "t_mm": [0, 0, 0]}},
  {"id": "b", "calibration": "b.json",
   "world_from_sensor": {"rvec": [0, 0.3, 0], "t_mm": [500, 0, 0]}}]}"#,
    )
    .unwrap();
    let points = dir.path().join("rig_points.csv");
    fs::write(
        &points,
        "sensor,point,x_mm,y_mm\na,1,0.1,0.2\nb,1,0.1,0.2\n",
    )
    .unwrap();
    let before = fs::read(&b).unwrap();
    let out = psdcal([
        "locate",
        "--rig",
        rig.to_str().unwrap(),
        "-p",
        points.to_str().unwrap(),
        "--out",
        b.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("listed in --rig"), "{err}");
    assert_eq!(fs::read(&b).unwrap(), before);
    assert!(fs::read(&a).is_ok());
}

#[test]
fn one_mistyped_led_is_named_not_blamed_on_the_poses() {
    let dir = tempfile::tempdir().unwrap();
    let text = fs::read_to_string(valid("template.csv")).unwrap();
    // The first LED's X with a digit too many.
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let row = lines
        .iter()
        .position(|l| l.chars().next().is_some_and(|c| c.is_ascii_digit()))
        .unwrap();
    let mut fields: Vec<String> = lines[row].split(',').map(str::to_string).collect();
    let led = fields[0].clone();
    fields[1] = format!("{}0", fields[1]);
    lines[row] = fields.join(",");
    let t = dir.path().join("template.csv");
    fs::write(&t, lines.join("\n") + "\n").unwrap();
    let o = valid("observations.csv").display().to_string();
    let cal = dir.path().join("cal.json");
    let out = psdcal([
        "calibrate",
        "-t",
        t.to_str().unwrap(),
        "-o",
        &o,
        "--out",
        cal.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains(&format!("contradict LED '{led}'")), "{err}");
    assert!(err.contains(&format!("line {}", row + 1)), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn a_report_on_a_degenerate_calibration_is_drawn() {
    // The reproducer's kind: a calibration with an absurd focal length is
    // drawn; one whose correction folds at once (its valid region is empty:
    // the PSD term's determinant is negative already at the optical centre)
    // is refused.
    let dir = tempfile::tempdir().unwrap();
    let text = fs::read_to_string(valid("calibration.json")).unwrap();
    // Edited as text: the file's order of names is part of its format.
    // Since calibration files are checked on reading as strictly as a
    // fresh calibration, the empty region is refused, naming the field.
    let folded = dir.path().join("l1.json");
    fs::write(&folded, text.replace("\"l1\": 0.0", "\"l1\": -1.0")).unwrap();
    let refused = dir.path().join("report-l1");
    let out = psdcal([
        "report",
        "-c",
        folded.to_str().unwrap(),
        "--out",
        refused.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("distortion.l1 = -1: the distortion correction folds"));
    assert_eq!(stderr(&out).lines().count(), 1, "{}", stderr(&out));
    assert!(!refused.exists());
    let cases = [("f", "\"f\": 8.0", "\"f\": 10000.0")];
    for (name, from, to) in cases {
        assert_eq!(text.matches(from).count(), 2, "{name}: the fixture changed");
        let cal = dir.path().join(format!("{name}.json"));
        fs::write(&cal, text.replace(from, to)).unwrap();
        let folder = dir.path().join(format!("report-{name}"));
        let out = psdcal([
            "report",
            "-c",
            cal.to_str().unwrap(),
            "--out",
            folder.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        let page = fs::read_to_string(folder.join("report.html")).unwrap();
        assert!(page.contains("<svg"), "{name}: no plot in the page");
        assert!(!stderr(&out).contains("cannot plot"), "{}", stderr(&out));
    }
}
