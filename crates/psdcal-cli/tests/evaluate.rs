//! `psdcal simulate-positioning` → `psdcal locate --rig` → `psdcal evaluate`
//! end to end, the JSON metrics against an independent computation from
//! the files, the report page, and bad input naming file and line.

mod common;

use std::fs;
use std::path::Path;

use common::{psdcal, stderr, stdout};

fn read_csv(path: &Path) -> Vec<Vec<String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let mut rows = vec![header];
    rows.extend(
        r.records()
            .map(|rec| rec.unwrap().iter().map(String::from).collect()),
    );
    rows
}

fn col(rows: &[Vec<String>], name: &str) -> usize {
    rows[0].iter().position(|h| h == name).unwrap()
}

fn close(a: f64, b: f64, what: &str) {
    assert!((a - b).abs() <= 1e-9 * b.abs(), "{what}: {a} against {b}");
}

/// The 0-based-rank definition-7 quantile, written independently.
fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let rank = 1.0 + (v.len() - 1) as f64 * q;
    let j = rank.floor() as usize;
    let g = rank - j as f64;
    let next = if j < v.len() { v[j] } else { v[j - 1] };
    (1.0 - g) * v[j - 1] + g * next
}

#[test]
fn simulate_locate_evaluate_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let room = dir.path().join("room");
    let out = psdcal([
        "simulate-positioning",
        "--lens",
        "2",
        "--snr",
        "40",
        "--emitters",
        "40",
        "--seed",
        "3",
        "--out",
        room.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("pass --point-sigma"),
        "{}",
        stdout(&out)
    );
    for f in [
        "rig.json",
        "rig_points.csv",
        "truth.csv",
        "s1/calibration.json",
        "s2/calibration.json",
    ] {
        assert!(room.join(f).is_file(), "{f}");
    }
    let est = room.join("estimates.csv");
    let out = psdcal([
        "-q",
        "locate",
        "--rig",
        room.join("rig.json").to_str().unwrap(),
        "--points",
        room.join("rig_points.csv").to_str().unwrap(),
        "--point-sigma",
        "0.0007",
        "--out",
        est.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report = dir.path().join("evaluation");
    let out = psdcal([
        "--json",
        "evaluate",
        "--truth",
        room.join("truth.csv").to_str().unwrap(),
        "--estimates",
        est.to_str().unwrap(),
        "--rig",
        room.join("rig.json").to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    // The page is psdcal's: an edited one is kept (issue 33), --force
    // replaces it.
    let page = report.join("evaluation.html");
    std::fs::write(&page, "my notes").unwrap();
    let truth = room.join("truth.csv");
    let again = |force: &[&str]| {
        let mut args = vec![
            "evaluate",
            "-q",
            "--truth",
            truth.to_str().unwrap(),
            "--estimates",
            est.to_str().unwrap(),
            "--report",
            report.to_str().unwrap(),
        ];
        args.extend_from_slice(force);
        psdcal(args)
    };
    let kept = again(&[]);
    assert_eq!(kept.status.code(), Some(1), "{}", stderr(&kept));
    assert!(stderr(&kept).contains("evaluation.html") && stderr(&kept).contains("--force"));
    assert_eq!(std::fs::read_to_string(&page).unwrap(), "my notes");
    assert!(again(&["--force"]).status.success());
    let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    // Independent computation from the two files.
    let truth = read_csv(&room.join("truth.csv"));
    let estimates = read_csv(&est);
    let mut errors = Vec::new();
    for t in &truth[1..] {
        let e = estimates[1..].iter().find(|e| e[0] == t[0]).unwrap();
        let get = |rows: &[Vec<String>], row: &[String], c: &str| -> f64 {
            row[col(rows, c)].parse().unwrap()
        };
        errors.push([
            get(&estimates, e, "x_world_mm") - get(&truth, t, "x_mm"),
            get(&estimates, e, "y_world_mm") - get(&truth, t, "y_mm"),
            get(&estimates, e, "z_world_mm") - get(&truth, t, "z_mm"),
        ]);
    }
    let n = errors.len() as f64;
    assert_eq!(json["n"], 40);
    assert_eq!(json["not_located"], 0);
    let d: Vec<f64> = errors
        .iter()
        .map(|e| (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt())
        .collect();
    let h: Vec<f64> = errors
        .iter()
        .map(|e| (e[0] * e[0] + e[1] * e[1]).sqrt())
        .collect();
    let f = |k: &str| json[k].as_f64().unwrap();
    close(f("mean_mm"), d.iter().sum::<f64>() / n, "mean");
    close(
        f("rms_mm"),
        (d.iter().map(|x| x * x).sum::<f64>() / n).sqrt(),
        "rms",
    );
    close(f("median_mm"), quantile(d.clone(), 0.5), "median");
    close(f("p75_mm"), quantile(d.clone(), 0.75), "p75");
    close(f("p95_mm"), quantile(d.clone(), 0.95), "p95");
    close(f("se95_mm"), quantile(d.clone(), 0.95), "se95");
    close(f("ce95_mm"), quantile(h, 0.95), "ce95");
    close(f("max_mm"), d.iter().cloned().fold(0.0, f64::max), "max");
    for k in 0..3 {
        let b = errors.iter().map(|e| e[k]).sum::<f64>() / n;
        close(json["bias_mm"][k].as_f64().unwrap(), b, "bias");
    }
    let w = f("within_95_ellipsoid");
    assert!((0.0..=1.0).contains(&w));
    // Lens 2 at 40 dB, 2.5 m: millimetres to a few centimetres, not metres.
    assert!(f("rms_mm") > 0.1 && f("rms_mm") < 100.0, "{}", f("rms_mm"));
    // The page: self-contained, three figures.
    let html = fs::read_to_string(report.join("evaluation.html")).unwrap();
    for bad in ["<script", "<link", "<img", "url(", "https://"] {
        assert!(!html.contains(bad), "{bad}");
    }
    assert_eq!(html.matches("<svg").count(), 3);
    assert!(html.contains("75th percentile (EvAAL score)"));
    for f in [
        "error_cdf.svg",
        "error_vectors.svg",
        "error_vs_distance.svg",
    ] {
        assert!(report.join(f).is_file(), "{f}");
    }
}

#[test]
fn bad_input_names_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let truth = dir.path().join("truth.csv");
    let est = dir.path().join("est.csv");
    fs::write(&truth, "emitter,x_mm,y_mm,z_mm\na,0,0,0\nb,1,2,3\n").unwrap();
    let cases = [
        ("emitter,x_mm,y_mm,z_mm\na,0,0,0\n", "truth.csv:3: emitter 'b' has no row in the estimates"),
        ("emitter,x_mm,y_mm,z_mm\na,0,0,0\nb,1,2,3\nc,0,0,0\n", "est.csv:4: emitter 'c' is not in the truth"),
        ("emitter,x_mm,y_mm,z_mm\na,0,0,0\nb,1,2,3\na,0,0,0\n", "est.csv:4: emitter 'a' appears twice (first on line 2)"),
        ("emitter,x_mm,y_mm,z_mm\na,0,0,nan\nb,1,2,3\n", "est.csv:2: column 'z_mm' (4): expected a finite number"),
        (
            "emitter,x_mm,y_mm,z_mm,sigma_x_mm,sigma_y_mm,sigma_z_mm,cov_xy_mm2,cov_xz_mm2,cov_yz_mm2\n\
             a,0,0,0,1,1,0,0,0,0\nb,1,2,3,1,1,1,0,0,0\n",
            "est.csv:2: the position covariance is singular",
        ),
    ];
    for (text, expected) in cases {
        fs::write(&est, text).unwrap();
        let out = psdcal([
            "evaluate",
            "--truth",
            truth.to_str().unwrap(),
            "--estimates",
            est.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(1), "{text}");
        let err = stderr(&out);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(expected), "{err}\nexpected: {expected}");
    }
}

#[test]
fn angles_from_aoa_are_evaluated_in_degrees() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("points.csv");
    fs::write(&points, "emitter,x_mm,y_mm\na,0.5,0.2\nb,-1,2\nc,3,-2\n").unwrap();
    let aoa = dir.path().join("aoa.csv");
    let calibration = common::valid("calibration.json");
    let out = psdcal([
        "-q",
        "aoa",
        "-c",
        calibration.to_str().unwrap(),
        "-p",
        points.to_str().unwrap(),
        "--point-sigma",
        "0.001",
        "--out",
        aoa.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    // The truth: every estimate off by (−0.01°, +0.005°).
    let rows = read_csv(&aoa);
    let (ax, ay) = (col(&rows, "alpha_x_deg"), col(&rows, "alpha_y_deg"));
    let mut truth = String::from("emitter,alpha_x_deg,alpha_y_deg\n");
    for r in &rows[1..] {
        let x: f64 = r[ax].parse().unwrap();
        let y: f64 = r[ay].parse().unwrap();
        truth.push_str(&format!("{},{},{}\n", r[0], x + 0.01, y - 0.005));
    }
    let truth_path = dir.path().join("truth.csv");
    fs::write(&truth_path, truth).unwrap();
    let out = psdcal([
        "--json",
        "evaluate",
        "--truth",
        truth_path.to_str().unwrap(),
        "--estimates",
        aoa.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    let a = &json["angles"];
    assert_eq!(a["n"], 3);
    let size = 0.01f64.hypot(0.005);
    for k in [
        "mean_deg",
        "median_deg",
        "rms_deg",
        "p75_deg",
        "p95_deg",
        "max_deg",
    ] {
        assert!((a[k].as_f64().unwrap() - size).abs() < 1e-9 * size, "{k}");
    }
    assert!((a["bias_deg"][0].as_f64().unwrap() + 0.01).abs() < 1e-11);
    assert!((a["bias_deg"][1].as_f64().unwrap() - 0.005).abs() < 1e-11);
    assert!(a["within_95_ellipse"].as_f64().is_some());
    assert!(json.get("mean_mm").is_none(), "no positions compared");
}

#[test]
fn impossible_rigs_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = psdcal([
        "simulate-positioning",
        "--sensors",
        "1",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let out = psdcal([
        "simulate-positioning",
        "--baseline",
        "30000",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("shorten the baseline"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn emitters_not_located_are_failures_not_silently_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let truth = dir.path().join("truth.csv");
    let est = dir.path().join("est.csv");
    fs::write(
        &truth,
        "emitter,x_mm,y_mm,z_mm\na,0,0,0\nb,100,0,0\nc,0,100,0\nd,0,0,100\ne,50,50,50\n",
    )
    .unwrap();
    // Errors 1, 2, 3, 4 mm along x; e not located.
    fs::write(
        &est,
        "emitter,sensors,x_world_mm,y_world_mm,z_world_mm,status\n\
         a,l;r,1,0,0,ok\nb,l;r,102,0,0,ok\nc,l;r,3,100,0,ok\nd,l;r,4,0,100,ok\n\
         e,l,,,,too_few_sensors\n",
    )
    .unwrap();
    let out = psdcal([
        "--json",
        "evaluate",
        "--truth",
        truth.to_str().unwrap(),
        "--estimates",
        est.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("counted as failures"),
        "{}",
        stderr(&out)
    );
    let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(json["n"], 4);
    assert_eq!(json["not_located"], 1);
    assert_eq!(json["attempted"], 5);
    assert_eq!(json["failures"], 1);
    close(json["success_rate"].as_f64().unwrap(), 0.8, "success rate");
    // Over the located only: p75 of 1, 2, 3, 4 is 3.25; with the failure
    // as +∞ (N = 5): the median is 3, the 75th percentile 4, the 95th
    // infinite (null), CE95 too.
    close(json["p75_mm"].as_f64().unwrap(), 3.25, "p75 located");
    close(
        json["median_with_failures_mm"].as_f64().unwrap(),
        3.0,
        "median",
    );
    close(json["p75_with_failures_mm"].as_f64().unwrap(), 4.0, "p75");
    assert!(json["p95_with_failures_mm"].is_null());
    assert!(json["ce95_with_failures_mm"].is_null());
    let out = psdcal([
        "evaluate",
        "--truth",
        truth.to_str().unwrap(),
        "--estimates",
        est.to_str().unwrap(),
    ]);
    let text = stdout(&out);
    assert!(text.contains("4 / 5 (80.0 %)"), "{text}");
    assert!(text.contains("infinite (too many failures)"), "{text}");
}
