//! Issue 12's reproducer through every command: a calibration whose
//! correction folds inside the active area (k1 = −0.02 mm⁻² about
//! (0.5, −0.7): det = (1 + 3 k1 r²)(1 + k1 r²) first vanishes at r* =
//! 1/√(3 · 0.02) = 4.08 mm) never answers `ok` past the fold — `aoa`,
//! `correct`, `locate` and `map` — whether the file stores its valid region
//! (version 2) or not (version 1).

mod common;

use std::fs;
use std::path::Path;

use common::{psdcal, stderr, stdout};
use psdcal_io::{read_calibration, write_calibration, Calibration, Covariance, StdDevs};
use psdcal_model::{Param, PsdGeometry, SensorModel};
use serde_json::Value;

fn folding(version: u32) -> Calibration {
    let mut model = SensorModel::pinhole(8.0, 0.5, -0.7);
    model.distortion.k1 = -0.02;
    let mut cal = Calibration::from_model(&model, &PsdGeometry::default());
    cal.set_estimated(&[Param::F]);
    cal.std = StdDevs(vec![("f".into(), 0.01)]);
    cal.covariance = Covariance {
        parameters: vec!["f".into()],
        matrix: vec![vec![1e-4]],
    };
    cal.version = version;
    if version >= 2 {
        cal.store_valid_region();
    }
    cal
}

fn run(args: &[&str]) -> (String, String) {
    let out = psdcal(args);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    (stdout(&out), stderr(&out))
}

/// The status column of a CSV text.
fn statuses(text: &str) -> Vec<String> {
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let status = reader
        .headers()
        .unwrap()
        .iter()
        .position(|h| h == "status")
        .unwrap();
    reader
        .records()
        .map(|r| r.unwrap()[status].to_string())
        .collect()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn no_command_answers_ok_past_the_fold() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("points.csv");
    // The centre, a point 3 mm out (inside), the reproducer's corner (7.21
    // mm out, where det > 0 again and the ideal point is mirrored), and a
    // point 4.3 mm out along +x (just past r*, det < 0).
    fs::write(
        &points,
        "name,x_mm,y_mm\ncentre,0.5,-0.7\nnear,3.5,-0.7\ncorner,-4.5,4.5\nedge,4.8,-0.7\n",
    )
    .unwrap();
    for version in [1, 2] {
        let cal = dir.path().join(format!("v{version}.json"));
        write_calibration(&cal, &folding(version)).unwrap();
        let stored = fs::read_to_string(&cal)
            .unwrap()
            .contains("\"valid_region\"");
        assert_eq!(stored, version == 2);
        assert_eq!(
            read_calibration(&cal).unwrap().valid_region(),
            folding(2).valid_region()
        );
        let expected = ["ok", "ok", "outside_valid_region", "outside_valid_region"];

        let (text, err) = run(&["aoa", "-c", s(&cal), "-p", s(&points)]);
        assert_eq!(statuses(&text), expected, "aoa v{version}");
        assert!(err.contains("2 ok, 2 outside_valid_region"), "{err}");
        assert!(err.contains("folds over"), "{err}");

        let (text, _) = run(&[
            "locate",
            "-c",
            s(&cal),
            "-p",
            s(&points),
            "--distance",
            "5000",
        ]);
        assert_eq!(statuses(&text), expected, "locate v{version}");

        let (text, err) = run(&["correct", "-c", s(&cal), "-p", s(&points)]);
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[3].starts_with("corner,-4.5,4.5,,"), "{text}");
        assert!(lines[4].starts_with("edge,4.8,-0.7,,"), "{text}");
        assert!(!lines[2].ends_with(",,"), "{text}");
        assert!(err.contains("outside_valid_region"), "{err}");

        let out = dir.path().join("map.csv");
        let (text, _) = run(&[
            "map",
            "-c",
            s(&cal),
            "--k-sigma",
            "2",
            "--grid",
            "9",
            "--json",
            "--out",
            s(&out),
        ]);
        let json: Value = serde_json::from_str(&text).unwrap();
        let map = fs::read_to_string(&out).unwrap();
        let st = statuses(&map);
        // Grid corners are 7.2 mm or more from the centre: past the fold.
        for corner in [0, 8, 72, 80] {
            assert_eq!(st[corner], "outside_valid_region", "map v{version}");
        }
        let refused = st.iter().filter(|s| *s == "outside_valid_region").count();
        assert_eq!(json["rows"]["not_answered"], refused);
        assert!(refused > 20 && refused < 81, "{refused}");
    }
}

#[test]
fn a_calibration_that_does_not_fold_answers_as_before() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("points.csv");
    fs::write(&points, "x_mm,y_mm\n-4.5,4.5\n4.5,-4.5\n0,0\n").unwrap();
    let mut cal = Calibration::from_model(&SensorModel::paper_lens2(), &PsdGeometry::default());
    let v1 = dir.path().join("v1.json");
    cal.version = 1;
    write_calibration(&v1, &cal).unwrap();
    cal.version = 2;
    cal.store_valid_region();
    assert!(cal.valid_region.as_ref().unwrap().whole_active_area);
    let v2 = dir.path().join("v2.json");
    write_calibration(&v2, &cal).unwrap();
    let (a1, _) = run(&["aoa", "-c", s(&v1), "-p", s(&points)]);
    let (a2, _) = run(&["aoa", "-c", s(&v2), "-p", s(&points)]);
    assert_eq!(a1, a2);
    assert_eq!(statuses(&a1), ["ok", "ok", "ok"]);
}
