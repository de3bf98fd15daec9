//! Happy paths of the `psdcal` binary, usage errors, and the valid fixtures.

mod common;

use std::fs;
use std::path::Path;

use common::{psdcal, stderr, stdout, valid};
use nalgebra::Vector2;
use psdcal_model::psd::impact_point_with_gains;
use psdcal_model::{Amplitudes, PsdGeometry};
use serde_json::Value;

#[test]
fn valid_fixtures_are_up_to_date() {
    let bless = std::env::var_os("PSDCAL_BLESS").is_some();
    for (name, content) in common::valid_fixtures() {
        let path = valid(name);
        if bless {
            fs::create_dir_all(common::data_dir("valid")).unwrap();
            fs::write(&path, &content).unwrap();
        }
        let committed = fs::read_to_string(&path).unwrap_or_default();
        assert!(
            committed == content,
            "{} differs from what tests/common/mod.rs generates; rerun with PSDCAL_BLESS=1",
            path.display()
        );
    }
}

fn check_json(extra: &[&str]) -> Value {
    let t = valid("template.csv");
    let o = valid("observations.csv");
    let mut args = vec![
        "--json".as_ref(),
        "check".as_ref(),
        "--template".as_ref(),
        t.as_os_str(),
        "--observations".as_ref(),
        o.as_os_str(),
    ];
    args.extend(extra.iter().map(|s| std::ffi::OsStr::new(*s)));
    let out = psdcal(args);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    serde_json::from_slice(&out.stdout).expect("check --json prints JSON")
}

#[test]
fn check_summarises_a_valid_data_set() {
    let out = psdcal([
        "check".as_ref(),
        "--template".as_ref(),
        valid("template.csv").as_os_str(),
        "--observations".as_ref(),
        valid("observations.csv").as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(stderr(&out), "");
    let text = stdout(&out);
    assert!(
        text.contains(
            "14 LEDs, 7 declared lines: r1 (5), c1 (3), c2 (3), c3 (3), c4 (3), r2 (4), r3 (5)"
        ),
        "{text}"
    );
    assert!(text.contains(": 56 rows\n"), "{text}");
    assert!(
        text.contains("sensor:        9 x 9 mm active area\n"),
        "{text}"
    );
    assert!(text.contains("image  points  x range (mm)"), "{text}");
    let json = check_json(&[]);
    for image in json["images"].as_array().unwrap() {
        let b = &image["bounds"];
        let row = format!(
            "{:<5}  {:>6}  {:<20}  {:.3} .. {:.3}\n",
            image["id"].as_str().unwrap(),
            14,
            format!(
                "{:.3} .. {:.3}",
                b["x_min_mm"].as_f64().unwrap(),
                b["x_max_mm"].as_f64().unwrap()
            ),
            b["y_min_mm"].as_f64().unwrap(),
            b["y_max_mm"].as_f64().unwrap()
        );
        assert!(text.contains(&row), "missing row {row:?} in\n{text}");
    }
    assert!(text.contains("total: 4 images, 56 points\n"), "{text}");
    assert!(text.contains("dropped:       nothing\n"), "{text}");
    let covered = json["coverage"]["cells_covered"].as_u64().unwrap();
    assert!(
        text.contains(&format!("coverage:      {covered} of 100 cells (")),
        "{text}"
    );
    let map: Vec<&str> = text.lines().filter(|l| l.contains('|')).collect();
    assert_eq!(map.len(), 10, "{text}");
    let hashes: usize = map.iter().map(|l| l.matches('#').count()).sum();
    assert_eq!(hashes as u64, covered);
}

#[test]
fn check_json_is_complete() {
    let json = check_json(&[]);
    assert_eq!(json["template"]["leds"], 14);
    assert_eq!(json["template"]["lines"].as_array().unwrap().len(), 7);
    assert_eq!(json["rows"], 56);
    assert_eq!(json["sensor"]["lx_mm"], 9.0);
    let ids: Vec<&str> = json["images"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["id"].as_str().unwrap())
        .collect();
    assert_eq!(ids, ["pose1", "pose2", "pose3", "pose4"]);
    assert!(json["images"]
        .as_array()
        .unwrap()
        .iter()
        .all(|i| i["points"] == 14));
    assert_eq!(json["total_points"], 56);
    assert_eq!(json["dropped_points"], 0);
    assert_eq!(json["dropped_images"], 0);
    assert_eq!(json["warnings"], serde_json::json!([]));
    let counts = json["coverage"]["counts"].as_array().unwrap();
    assert_eq!(counts.len(), 10);
    let total: u64 = counts
        .iter()
        .flat_map(|r| r.as_array().unwrap())
        .map(|c| c.as_u64().unwrap())
        .sum();
    assert_eq!(total, 56);
    let covered = json["coverage"]["cells_covered"].as_u64().unwrap();
    assert_eq!(
        json["coverage"]["fraction"].as_f64().unwrap(),
        covered as f64 / 100.0
    );
    // The fixture spreads its points: more than a quarter of the cells.
    assert!(covered > 25, "{covered}");
}

#[test]
fn check_with_signals_gives_the_same_points() {
    let from_obs = check_json(&[]);
    let out = psdcal([
        "check".as_ref(),
        "--json".as_ref(),
        "-t".as_ref(),
        valid("template.csv").as_os_str(),
        "--signals".as_ref(),
        valid("signals.csv").as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let from_sig: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(from_sig["total_points"], 56);
    for (a, b) in from_obs["images"]
        .as_array()
        .unwrap()
        .iter()
        .zip(from_sig["images"].as_array().unwrap())
    {
        for key in ["x_min_mm", "x_max_mm", "y_min_mm", "y_max_mm"] {
            let (a, b) = (
                a["bounds"][key].as_f64().unwrap(),
                b["bounds"][key].as_f64().unwrap(),
            );
            assert!((a - b).abs() < 1e-12, "{key}: {a} vs {b}");
        }
    }
}

#[test]
fn check_quiet_prints_nothing() {
    let out = psdcal([
        "--quiet".as_ref(),
        "check".as_ref(),
        "-t".as_ref(),
        valid("template.csv").as_os_str(),
        "-o".as_ref(),
        valid("observations.csv").as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(stdout(&out), "");
    assert_eq!(stderr(&out), "");
}

#[test]
fn check_drops_off_sensor_points_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let obs = dir.path().join("observations.csv");
    let mut text = fs::read_to_string(valid("observations.csv")).unwrap();
    text.push_str("pose5,1,5.5,0\n");
    let off_line = text.lines().count();
    fs::write(&obs, text).unwrap();
    let out = psdcal([
        "check".as_ref(),
        "-t".as_ref(),
        valid("template.csv").as_os_str(),
        "-o".as_ref(),
        obs.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains(&format!(
            "warning: {}:{off_line}: image 'pose5', LED '1': point (5.5, 0) mm is off the 9 x 9 \
             mm active area: point dropped\n",
            obs.display()
        )),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "warning: {}:{off_line}: image 'pose5' has 0 points on the sensor",
            obs.display()
        )),
        "{err}"
    );
    let json: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["dropped_points"], 1);
    assert_eq!(json["dropped_images"], 1);
    assert_eq!(json["warnings"][0]["kind"], "point_off_sensor");
    assert_eq!(json["warnings"][0]["line"], off_line);
    // Under --strict the same data set fails.
    let out = psdcal([
        "check".as_ref(),
        "-t".as_ref(),
        valid("template.csv").as_os_str(),
        "-o".as_ref(),
        obs.as_os_str(),
        "--strict".as_ref(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).starts_with(&format!("error: {}:{off_line}: ", obs.display())));
}

/// Parses a CSV produced by `correct` (no quoted commas in the numbers).
fn parse_csv(text: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut reader = csv::ReaderBuilder::new().from_reader(text.as_bytes());
    let header = reader
        .headers()
        .unwrap()
        .iter()
        .map(str::to_string)
        .collect();
    let rows = reader
        .records()
        .map(|r| r.unwrap().iter().map(str::to_string).collect())
        .collect();
    (header, rows)
}

#[test]
fn correct_writes_ideal_points_to_stdout() {
    let out = psdcal([
        "correct".as_ref(),
        "--calibration".as_ref(),
        valid("calibration.json").as_os_str(),
        "--points".as_ref(),
        valid("points.csv").as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // The table is on standard output: the summary goes to standard error.
    assert_eq!(
        stderr(&out),
        format!(
            "corrected 10 points of {} with {}: 10 ok\n",
            valid("points.csv").display(),
            valid("calibration.json").display()
        )
    );
    let (header, rows) = parse_csv(&stdout(&out));
    assert_eq!(
        header,
        [
            "id",
            "note",
            "x_mm",
            "y_mm",
            "extra",
            "x_ideal_mm",
            "y_ideal_mm",
            "status"
        ]
    );
    let inputs = common::points_to_correct();
    assert_eq!(rows.len(), inputs.len());
    let model = psdcal_model::Model::standard(&common::model());
    for (k, (row, p)) in rows.iter().zip(&inputs).enumerate() {
        assert_eq!(row[0], format!("p{k}"));
        assert_eq!(row[1], format!("note, {k}"));
        assert_eq!(row[2], p.x.to_string());
        assert_eq!(row[3], p.y.to_string());
        assert_eq!(row[4], " x ");
        let ideal = model.ideal(p);
        let x: f64 = row[5].parse().unwrap();
        let y: f64 = row[6].parse().unwrap();
        assert!((x - ideal.x).abs() <= 1e-12, "{x} vs {}", ideal.x);
        assert!((y - ideal.y).abs() <= 1e-12, "{y} vs {}", ideal.y);
        assert_eq!(row[7], "ok");
    }
}

#[test]
fn correct_writes_a_file_atomically_with_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out_path = dir.path().join("ideal.csv");
    fs::write(&out_path, "old content").unwrap();
    let out = psdcal([
        "correct".as_ref(),
        "-c".as_ref(),
        valid("calibration.json").as_os_str(),
        "-p".as_ref(),
        valid("points.csv").as_os_str(),
        "--out".as_ref(),
        out_path.as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let n = common::points_to_correct().len();
    assert_eq!(
        stdout(&out),
        format!(
            "corrected {n} points of {} with {}: {n} ok; wrote {} (added x_ideal_mm, \
             y_ideal_mm, status)\n",
            valid("points.csv").display(),
            valid("calibration.json").display(),
            out_path.display()
        )
    );
    let to_stdout = psdcal([
        "correct".as_ref(),
        "-c".as_ref(),
        valid("calibration.json").as_os_str(),
        "-p".as_ref(),
        valid("points.csv").as_os_str(),
    ]);
    assert_eq!(fs::read(&out_path).unwrap(), to_stdout.stdout);
    let names: Vec<String> = fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["ideal.csv"]);
    // --json: the summary as JSON.
    let out = psdcal([
        "correct".as_ref(),
        "--json".as_ref(),
        "-c".as_ref(),
        valid("calibration.json").as_os_str(),
        "-p".as_ref(),
        valid("points.csv").as_os_str(),
        "--out".as_ref(),
        out_path.as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let json: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["rows"]["rows"], n);
    assert_eq!(json["rows"]["status"]["ok"], n);
    assert_eq!(json["from_amplitudes"], false);
    assert_eq!(
        json["added_columns"],
        serde_json::json!(["x_ideal_mm", "y_ideal_mm", "status"])
    );
}

#[test]
fn correct_amplitudes_divides_the_calibration_gains() {
    let out = psdcal([
        "correct".as_ref(),
        "-c".as_ref(),
        valid("calibration.json").as_os_str(),
        "-p".as_ref(),
        valid("points_amplitudes.csv").as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let (header, rows) = parse_csv(&stdout(&out));
    assert_eq!(
        header,
        [
            "vx1",
            "vx2",
            "vy1",
            "vy2",
            "tag",
            "x_mm",
            "y_mm",
            "x_ideal_mm",
            "y_ideal_mm",
            "status"
        ]
    );
    let model = psdcal_model::Model::standard(&common::model());
    let inputs = common::points_to_correct();
    assert_eq!(rows.len(), inputs.len());
    for (k, (row, p)) in rows.iter().zip(&inputs).enumerate() {
        assert_eq!(row[4], format!("t{k}"));
        let v: Vec<f64> = row[..4].iter().map(|s| s.parse().unwrap()).collect();
        let amps = Amplitudes {
            vx1: v[0],
            vx2: v[1],
            vy1: v[2],
            vy2: v[3],
        };
        let measured =
            impact_point_with_gains(&PsdGeometry::default(), &amps, &common::gains()).unwrap();
        let got = |i: usize| -> f64 { row[i].parse().unwrap() };
        assert!((got(5) - measured.x).abs() <= 1e-12);
        assert!((got(6) - measured.y).abs() <= 1e-12);
        // The gains were divided out: the measured point is the true one.
        assert!((Vector2::new(got(5), got(6)) - p).norm() <= 1e-12);
        let ideal = model.ideal(&measured);
        assert!((got(7) - ideal.x).abs() <= 1e-12);
        assert!((got(8) - ideal.y).abs() <= 1e-12);
    }
}

#[test]
fn correct_warns_about_points_off_the_area() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("points.csv");
    fs::write(&points, "x_mm,y_mm\n0,0\n4.6,0\n").unwrap();
    let out = psdcal([
        "correct".as_ref(),
        "-c".as_ref(),
        valid("calibration.json").as_os_str(),
        "-p".as_ref(),
        points.as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        stderr(&out),
        format!(
            "warning: {p}:3: point (4.6, 0.0) mm is off the active area, where the model was not \
             fitted; answered anyway\ncorrected 2 points of {p} with {}: 1 ok, 1 \
             off_active_area\n",
            valid("calibration.json").display(),
            p = points.display()
        )
    );
    assert_eq!(stdout(&out).lines().count(), 3);
}

#[test]
fn usage_errors_exit_2() {
    let t = valid("template.csv");
    let o = valid("observations.csv");
    let cases: Vec<Vec<&std::ffi::OsStr>> = vec![
        vec![],
        vec!["frobnicate".as_ref()],
        vec!["check".as_ref()],
        vec!["check".as_ref(), "-t".as_ref(), t.as_os_str()],
        vec![
            "check".as_ref(),
            "-t".as_ref(),
            t.as_os_str(),
            "-o".as_ref(),
            o.as_os_str(),
            "-s".as_ref(),
            o.as_os_str(),
        ],
        vec![
            "check".as_ref(),
            "-t".as_ref(),
            t.as_os_str(),
            "-o".as_ref(),
            o.as_os_str(),
            "--lx".as_ref(),
            "-1".as_ref(),
        ],
        vec!["correct".as_ref(), "-c".as_ref(), "c.json".as_ref()],
        vec![
            "--json".as_ref(),
            "correct".as_ref(),
            "-c".as_ref(),
            "c.json".as_ref(),
            "-p".as_ref(),
            "p.csv".as_ref(),
        ],
        vec!["check".as_ref(), "--bogus".as_ref()],
    ];
    for args in cases {
        let out = psdcal(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains("error"), "{args:?}");
        assert!(!stderr(&out).contains("panicked"));
    }
}

#[test]
fn version_and_help() {
    let out = psdcal(["--version"]);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        stdout(&out),
        format!("psdcal {}\n", env!("CARGO_PKG_VERSION"))
    );
    for (command, example) in [
        ("check", "psdcal check --template data/example/template.csv"),
        (
            "correct",
            "psdcal correct --calibration calibration.json --points points.csv --out ideal.csv",
        ),
    ] {
        let out = psdcal([command, "--help"]);
        assert_eq!(out.status.code(), Some(0));
        let help = stdout(&out);
        assert!(help.contains("Example:"), "{help}");
        assert!(help.contains(example), "{help}");
    }
    let out = psdcal(["--help"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(stdout(&out).contains("Exit codes: 0 success, 1 failure"));
}

#[test]
fn readme_main_job_runs_on_the_example_data() {
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/example");
    let out = psdcal([
        "check".as_ref(),
        "--template".as_ref(),
        example.join("template.csv").as_os_str(),
        "--observations".as_ref(),
        example.join("observations.csv").as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stdout(&out).contains("total: 9 images, 126 points"));
}
