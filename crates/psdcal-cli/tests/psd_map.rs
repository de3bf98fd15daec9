//! The PSD map from the command line (docs/model.md §8.3): `simulate-scan`
//! → `psd-map` (with `--report`) → `calibrate --psd-map` → `aoa`, and the
//! bad inputs (a report over the scan too), each one clear line naming the
//! file.

mod common;

use common::{psdcal, stderr, stdout};

#[test]
fn scan_map_calibrate_and_answer() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    let run = psdcal([
        "simulate-scan",
        "--step",
        "0.5",
        "--stage-sigma",
        "0.3",
        "--snr",
        "50",
        "--out",
        &p("scan.csv"),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(
        stdout(&run).contains("19 × 19 positions"),
        "{}",
        stdout(&run)
    );
    let run = psdcal([
        "--json",
        "psd-map",
        "--scan",
        &p("scan.csv"),
        "--out",
        &p("map.json"),
        "--report",
        &p("map_report"),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    for file in ["psd_map.html", "psd_map_field.svg", "psd_map_residuals.png"] {
        assert!(dir.path().join("map_report").join(file).exists(), "{file}");
    }
    // A report over its own scan: one line, nothing written.
    std::fs::copy(p("scan.csv"), p("map_report/psd_map_field.svg")).unwrap();
    let refused = psdcal([
        "psd-map",
        "--scan",
        &p("map_report/psd_map_field.svg"),
        "--out",
        &p("map2.json"),
        "--report",
        &p("map_report"),
    ]);
    assert!(!refused.status.success());
    let err = stderr(&refused);
    assert!(
        err.contains("would overwrite the input given with --scan"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!dir.path().join("map2.json").exists());
    // That figure is no longer the one psdcal wrote: kept (issue 33) until
    // --force.
    let report_again = |force: &[&str]| {
        let mut args = vec![
            "psd-map".to_string(),
            "--scan".into(),
            p("scan.csv"),
            "--out".into(),
            p("map2.json"),
            "--report".into(),
            p("map_report"),
        ];
        args.extend(force.iter().map(|a| a.to_string()));
        psdcal(args)
    };
    let kept = report_again(&[]);
    assert_eq!(kept.status.code(), Some(1), "{}", stderr(&kept));
    assert!(
        stderr(&kept).contains("psd_map_field.svg"),
        "{}",
        stderr(&kept)
    );
    assert!(report_again(&["--force"]).status.success());
    let json: serde_json::Value = serde_json::from_str(&stdout(&run)).unwrap();
    assert_eq!(json["format"], "psdcal-psd-map");
    // 361 points: the map's error is a fraction of the ~0.37 µm noise.
    let fit = &json["fit"];
    assert!(fit["cv_rms_um"].as_f64().unwrap() < 1.0, "{fit}");
    assert!(fit["map_sigma_um"].as_f64().unwrap() < 0.37, "{fit}");
    let run = psdcal([
        "psd-map",
        "--scan",
        &p("scan.csv"),
        "--model",
        "poly:5",
        "--out",
        &p("m5.json"),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(
        stdout(&run).contains("model poly:5 (21 coefficients per axis)"),
        "{}",
        stdout(&run)
    );
    assert!(stdout(&run).contains("residual RMS per cell"));

    let sim = p("sim");
    assert!(psdcal([
        "-q",
        "simulate",
        "--snr",
        "40",
        "--images",
        "12",
        "--psd-nonlinearity",
        "--out",
        &sim
    ])
    .status
    .success());
    // `calibrate` of the simulated set with the map, then `extra`.
    let (template, observations) = (
        format!("{sim}/template.csv"),
        format!("{sim}/observations.csv"),
    );
    let map = p("map.json");
    let calibrate = |extra: &[&str]| {
        let mut args = vec![
            "-q",
            "calibrate",
            "-t",
            &template,
            "-o",
            &observations,
            "--psd-map",
            &map,
        ];
        args.extend_from_slice(extra);
        psdcal(args)
    };
    let run = calibrate(&["--out", &p("cal.json")]);
    assert!(run.status.success(), "{}", stderr(&run));
    std::fs::write(p("pts.csv"), "x_mm,y_mm\n0.5,0.5\n6,0\n").unwrap();
    let run = psdcal([
        "aoa",
        "--calibration",
        &p("cal.json"),
        "--points",
        &p("pts.csv"),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let out = stdout(&run);
    assert!(
        out.contains(",ok\n") && out.contains("outside_valid_region"),
        "{out}"
    );

    // The map refined: its stage lists its coefficients as estimated and
    // carries their covariance; aoa answers from it alone.
    let run = calibrate(&["--refine-psd-map", "--out", &p("refined.json")]);
    assert!(run.status.success(), "{}", stderr(&run));
    let cal: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("refined.json")).unwrap()).unwrap();
    let stage = cal["stages"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["kind"] == "psd_map")
        .unwrap();
    let k = stage["parameters"].as_object().unwrap().len();
    assert_eq!(stage["estimated"].as_array().unwrap().len(), k);
    assert_eq!(stage["covariance"]["matrix"].as_array().unwrap().len(), k);
    assert_eq!(cal["provenance"]["options"]["refine_psd_map"], true);
    let run = psdcal([
        "aoa",
        "--calibration",
        &p("refined.json"),
        "--points",
        &p("pts.csv"),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    // --refine-psd-map needs --psd-map.
    let run = psdcal([
        "calibrate",
        "-t",
        &format!("{sim}/template.csv"),
        "-o",
        &format!("{sim}/observations.csv"),
        "--refine-psd-map",
        "--out",
        &p("cal3.json"),
    ]);
    assert!(!run.status.success());
    assert!(stderr(&run).contains("--psd-map"), "{}", stderr(&run));

    // A map of another sensor size, named.
    let run = psdcal([
        "calibrate",
        "-t",
        &format!("{sim}/template.csv"),
        "-o",
        &format!("{sim}/observations.csv"),
        "--lx",
        "10",
        "--ly",
        "10",
        "--psd-map",
        &p("map.json"),
        "--out",
        &p("cal2.json"),
    ]);
    assert_eq!(run.status.code(), Some(1));
    let err = stderr(&run);
    assert!(
        err.contains("map.json") && err.contains("9 mm × 9 mm"),
        "{err}"
    );
}

#[test]
fn bad_scans_are_one_clear_line() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    std::fs::write(
        p("dup.csv"),
        "x_stage_mm,y_stage_mm,x_mm,y_mm\n0,0,0,0\n1,0,1,0\n0,0,0,0\n",
    )
    .unwrap();
    let run = psdcal(["psd-map", "--scan", &p("dup.csv"), "--out", &p("m.json")]);
    assert_eq!(run.status.code(), Some(1));
    let err = stderr(&run);
    assert!(
        err.contains("dup.csv:4") && err.contains("first on line 2"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");

    let mut few = String::from("x_stage_mm,y_stage_mm,x_mm,y_mm\n");
    for i in 0..4 {
        for j in 0..4 {
            few.push_str(&format!("{i},{j},{i},{j}\n"));
        }
    }
    std::fs::write(p("few.csv"), few).unwrap();
    let run = psdcal([
        "psd-map",
        "--scan",
        &p("few.csv"),
        "--model",
        "poly:6",
        "--out",
        &p("m.json"),
    ]);
    assert_eq!(run.status.code(), Some(1));
    let err = stderr(&run);
    assert!(
        err.contains("few.csv") && err.contains("too few for poly:6"),
        "{err}"
    );
    assert!(!dir.path().join("m.json").exists());
}

/// A realistic data set whose every point lies inside the scan's hull is
/// calibrated with the map, and every test point inside the hull gets an
/// angle (docs/model.md §8.2: the hull's edge is checked exactly, not by the
/// chord between two rays, and is no fold). This seed's point 63 µm inside
/// the hull, near one of its corners, was refused as "past a fold" when the
/// region cut the hull's corners; 28 of 1 521 grid points inside the hull
/// went unanswered.
#[test]
fn data_and_test_points_inside_the_scan_are_never_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    let ok = |args: &[&str]| {
        let run = psdcal(args);
        assert!(run.status.success(), "{args:?}: {}", stderr(&run));
    };
    ok(&[
        "-q",
        "simulate-scan",
        "--snr",
        "50",
        "--seed",
        "116",
        "--out",
        &p("scan.csv"),
    ]);
    ok(&[
        "-q",
        "psd-map",
        "--scan",
        &p("scan.csv"),
        "--out",
        &p("map.json"),
    ]);
    ok(&[
        "-q",
        "simulate",
        "--lens",
        "1",
        "--snr",
        "40",
        "--images",
        "15",
        "--seed",
        "16",
        "--psd-nonlinearity",
        "--out",
        &p("set"),
    ]);
    ok(&[
        "-q",
        "calibrate",
        "--template",
        &p("set/template.csv"),
        "--observations",
        &p("set/observations.csv"),
        "--psd-map",
        &p("map.json"),
        "--out",
        &p("cal.json"),
    ]);
    // The grid points strictly inside the hull (its vertices from the map
    // file; the half-plane test written here).
    let map: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("map.json")).unwrap()).unwrap();
    let hull: Vec<(f64, f64)> = map["stage"]["hull_mm"]
        .as_array()
        .expect("the map's hull")
        .iter()
        .map(|v| (v[0].as_f64().unwrap(), v[1].as_f64().unwrap()))
        .collect();
    let inside = |x: f64, y: f64| {
        (0..hull.len()).all(|i| {
            let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
            let (ex, ey) = (b.0 - a.0, b.1 - a.1);
            (ex * (y - a.1) - ey * (x - a.0)) / ex.hypot(ey) > 1e-6
        })
    };
    let mut points = String::from("x_mm,y_mm\n");
    let mut n = 0;
    for i in 0..41 {
        for j in 0..41 {
            let (x, y) = (-4.5 + 0.225 * i as f64, -4.5 + 0.225 * j as f64);
            if inside(x, y) {
                points.push_str(&format!("{x},{y}\n"));
                n += 1;
            }
        }
    }
    assert!(n > 1400, "{n} grid points inside the hull");
    std::fs::write(p("grid.csv"), points).unwrap();
    ok(&[
        "-q",
        "aoa",
        "--calibration",
        &p("cal.json"),
        "--points",
        &p("grid.csv"),
        "--out",
        &p("aoa.csv"),
    ]);
    let mut reader = csv::Reader::from_path(p("aoa.csv")).unwrap();
    let status = reader
        .headers()
        .unwrap()
        .iter()
        .position(|h| h == "status")
        .unwrap();
    let rows: Vec<_> = reader.records().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), n);
    assert!(rows.iter().all(|r| &r[status] == "ok"));
}
