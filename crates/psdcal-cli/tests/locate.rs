//! `psdcal aoa`, `psdcal locate` and `psdcal map` end to end: values against
//! the library, round trips through files, statuses of unanswerable rows,
//! malformed rig files, usage errors.

mod common;

use std::fs;
use std::path::Path;

use common::{psdcal, stderr, stdout, valid};
use nalgebra::{Vector2, Vector3};
use psdcal_io::{read_calibration, write_calibration, Calibration};
use psdcal_locate::{
    angle_of_arrival, error_map, measured_from_ray, ErrorSource, MapOptions, ParameterErrors,
};
use psdcal_model::psd::electrode_currents;
use psdcal_model::{Param, Pose, PsdGeometry, SensorModel};
use serde_json::Value;

/// A CSV table: header and rows of text.
fn table(text: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .flexible(true)
        .from_reader(text.as_bytes());
    let header = reader.headers().unwrap().iter().map(String::from).collect();
    let rows = reader
        .records()
        .map(|r| r.unwrap().iter().map(String::from).collect())
        .collect();
    (header, rows)
}

fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

fn value(header: &[String], row: &[String], name: &str) -> f64 {
    row[column(header, name)].parse().unwrap()
}

fn run_ok(args: &[&str]) -> (String, String) {
    let out = psdcal(args);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    (stdout(&out), stderr(&out))
}

#[test]
fn aoa_keeps_the_input_and_matches_the_library() {
    let cal = valid("calibration.json");
    let points = valid("points.csv");
    let (text, err) = run_ok(&[
        "aoa",
        "-c",
        cal.to_str().unwrap(),
        "-p",
        points.to_str().unwrap(),
        "--point-sigma",
        "0.001",
    ]);
    // Table on standard output, summary on standard error.
    assert!(err.contains("aoa: 10 points of"), "{err}");
    assert!(err.contains(": 10 ok"), "{err}");
    let (header, rows) = table(&text);
    assert_eq!(&header[..5], ["id", "note", "x_mm", "y_mm", "extra"]);
    assert_eq!(header.last().unwrap(), "status");
    let model = read_calibration(&cal).unwrap().to_model();
    let input = table(&fs::read_to_string(&points).unwrap());
    for (row, original) in rows.iter().zip(&input.1) {
        assert_eq!(
            &row[..5],
            &original[..5],
            "input columns are kept as written"
        );
        let m = Vector2::new(value(&header, row, "x_mm"), value(&header, row, "y_mm"));
        let aoa = angle_of_arrival(&psdcal_model::Model::standard(&model), &m).unwrap();
        assert_eq!(value(&header, row, "alpha_x_deg"), aoa.alpha.x.to_degrees());
        assert_eq!(value(&header, row, "alpha_y_deg"), aoa.alpha.y.to_degrees());
        let ray = Vector3::new(
            value(&header, row, "ray_x"),
            value(&header, row, "ray_y"),
            value(&header, row, "ray_z"),
        );
        assert!((ray.norm() - 1.0).abs() < 1e-15);
        // Total² = calibration² + point² on each axis.
        for axis in ["x", "y"] {
            let total = value(&header, row, &format!("sigma_alpha_{axis}_deg"));
            let cal = value(&header, row, &format!("sigma_alpha_{axis}_cal_deg"));
            let point = value(&header, row, &format!("sigma_alpha_{axis}_point_deg"));
            assert!(cal > 0.0 && point > 0.0);
            assert!((total * total - cal * cal - point * point).abs() < 1e-12 * total * total);
        }
        let last = row.len() - 1;
        // The last two points are the centre and an off-area corner.
        assert!(
            row[last] == "ok" || row[last] == "off_active_area",
            "{row:?}"
        );
    }
}

#[test]
fn aoa_of_amplitudes_equals_aoa_of_points() {
    let cal = valid("calibration.json");
    let dir = tempfile::tempdir().unwrap();
    let out_points = dir.path().join("a.csv");
    let out_amps = dir.path().join("b.csv");
    for (input, out) in [
        ("points.csv", &out_points),
        ("points_amplitudes.csv", &out_amps),
    ] {
        let (text, _) = run_ok(&[
            "aoa",
            "-c",
            cal.to_str().unwrap(),
            "-p",
            valid(input).to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(text.contains("10 ok; wrote"), "{text}");
    }
    let (ha, ra) = table(&fs::read_to_string(&out_points).unwrap());
    let (hb, rb) = table(&fs::read_to_string(&out_amps).unwrap());
    assert_eq!(
        &hb[..7],
        ["vx1", "vx2", "vy1", "vy2", "tag", "x_mm", "y_mm"]
    );
    for (a, b) in ra.iter().zip(&rb) {
        for name in ["x_mm", "alpha_x_deg", "alpha_y_deg", "sigma_alpha_x_deg"] {
            let (va, vb) = (value(&ha, a, name), value(&hb, b, name));
            assert!(
                (va - vb).abs() < 1e-9 * va.abs().max(1.0),
                "{name}: {va} vs {vb}"
            );
        }
    }
}

#[test]
fn aoa_rows_that_cannot_be_answered_carry_a_status() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("p.csv");
    fs::write(
        &points,
        "name,x_mm,y_mm\ngood,1,1\nfar,1e300,0\nedge,4.8,0\n",
    )
    .unwrap();
    let amps = dir.path().join("a.csv");
    fs::write(&amps, "vx1,vx2,vy1,vy2\n1,1,1,1\n0,0,0,0\n").unwrap();
    let cal = valid("calibration.json");
    let out = dir.path().join("o.csv");
    let (text, err) = run_ok(&[
        "aoa",
        "-c",
        cal.to_str().unwrap(),
        "-p",
        points.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        text.contains("1 ok, 1 off_active_area, 1 outside_valid_region (1 not answered)"),
        "{text}"
    );
    assert!(
        err.contains("p.csv:3: measured point (1e300, 0.0) mm is outside"),
        "{err}"
    );
    assert!(
        err.contains("p.csv:4: point (4.8, 0.0) mm is off the active area"),
        "{err}"
    );
    let written = fs::read_to_string(&out).unwrap();
    assert!(!written.to_lowercase().contains("nan") && !written.contains("inf"));
    let (header, rows) = table(&written);
    let status = column(&header, "status");
    assert_eq!(rows[1][status], "outside_valid_region");
    assert_eq!(rows[1][column(&header, "alpha_x_deg")], "");
    assert_eq!(rows[2][status], "off_active_area");
    assert!(value(&header, &rows[2], "alpha_x_deg") > 0.0);
    let (_, err) = run_ok(&[
        "aoa",
        "-c",
        cal.to_str().unwrap(),
        "-p",
        amps.to_str().unwrap(),
    ]);
    assert!(err.contains("1 ok, 1 no_light (1 not answered)"), "{err}");
}

#[test]
fn locate_on_planes_round_trips_and_flags_misses() {
    let cal = valid("calibration.json");
    let model = read_calibration(&cal).unwrap().to_model();
    let dir = tempfile::tempdir().unwrap();
    // Emitters 5 m away, measured through the fixture's model.
    let emitters: Vec<Vector3<f64>> = [(-1500.0, -900.0), (0.0, 0.0), (800.0, 1700.0)]
        .iter()
        .map(|&(x, y)| Vector3::new(x, y, 5000.0))
        .collect();
    let mut csv_text = String::from("emitter,x_mm,y_mm\n");
    for (k, e) in emitters.iter().enumerate() {
        let m = measured_from_ray(
            &psdcal_model::Model::standard(&model),
            &Vector2::new(e.x / e.z, e.y / e.z),
        )
        .unwrap();
        csv_text.push_str(&format!("e{k},{},{}\n", m.x, m.y));
    }
    let points = dir.path().join("p.csv");
    fs::write(&points, csv_text).unwrap();
    let out = dir.path().join("o.csv");
    let (text, _) = run_ok(&[
        "locate",
        "-c",
        cal.to_str().unwrap(),
        "-p",
        points.to_str().unwrap(),
        "--distance",
        "5000",
        "--point-sigma",
        "0.001",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(text.contains("3 ok; wrote"), "{text}");
    let (header, rows) = table(&fs::read_to_string(&out).unwrap());
    for (row, e) in rows.iter().zip(&emitters) {
        let got = Vector3::new(
            value(&header, row, "x_sensor_mm"),
            value(&header, row, "y_sensor_mm"),
            value(&header, row, "z_sensor_mm"),
        );
        assert!((got - e).norm() < 1e-9, "{got:?} vs {e:?}");
        // A plane parallel to the sensor fixes z exactly.
        assert_eq!(value(&header, row, "sigma_z_sensor_mm"), 0.0);
        // 1 µm at f = 8 mm is about 0.6 mm at 5 m, the calibration adds to it.
        let sx = value(&header, row, "sigma_x_sensor_mm");
        assert!(sx > 0.6 && sx < 20.0, "{sx}");
    }
    // A wall at x = 100 mm: rays to the left point away from it.
    let (text, err) = run_ok(&[
        "locate",
        "-c",
        cal.to_str().unwrap(),
        "-p",
        points.to_str().unwrap(),
        "--plane",
        "1,0,0,100",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    let json: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(json["rows"]["not_answered"], 2, "{json}");
    assert_eq!(
        json["rows"]["status"]["points_away_from_plane"], 1,
        "{json}"
    );
    assert_eq!(json["rows"]["status"]["parallel_to_plane"], 1, "{json}");
    assert!(err.contains("points away from the plane"), "{err}");
}

/// Writes a rig of three sensors (both lenses, one pose given as
/// sensor_from_world) with its calibrations into `dir`; returns the rig's
/// path and the sensors' models and world_from_sensor poses.
fn write_rig(dir: &Path) -> (std::path::PathBuf, Vec<(String, SensorModel, Pose)>) {
    let mut lens1 = SensorModel::paper_lens1();
    lens1.distortion.l1 = SensorModel::PAPER_L1;
    let sensors = vec![
        (
            "left",
            SensorModel::paper_lens2(),
            Vector3::new(-1500.0, -1000.0, 2500.0),
        ),
        ("right", lens1, Vector3::new(1500.0, -1000.0, 2500.0)),
        (
            "back",
            SensorModel::paper_lens2(),
            Vector3::new(0.0, 1200.0, 2600.0),
        ),
    ];
    fs::create_dir_all(dir.join("cal")).unwrap();
    let mut entries = Vec::new();
    let mut out = Vec::new();
    for (k, (id, model, origin)) in sensors.into_iter().enumerate() {
        // Look at the origin of the world.
        let z = (-origin).normalize();
        let x = Vector3::x().cross(&z).normalize();
        let y = z.cross(&x);
        let pose = Pose::from_rotation(&nalgebra::Matrix3::from_columns(&[x, y, z]), origin);
        let cal = Calibration::from_model(&model, &PsdGeometry::default());
        write_calibration(dir.join("cal").join(format!("{id}.json")), &cal).unwrap();
        let (field, written) = if k == 1 {
            ("sensor_from_world", pose.inverse())
        } else {
            ("world_from_sensor", pose)
        };
        entries.push(format!(
            r#"{{"id": "{id}", "calibration": "cal/{id}.json", "{field}": {{"rvec": [{}, {}, {}], "t_mm": [{}, {}, {}]}}}}"#,
            written.rvec.x, written.rvec.y, written.rvec.z, written.t.x, written.t.y, written.t.z
        ));
        out.push((id.to_string(), model, pose));
    }
    let rig = dir.join("rig.json");
    fs::write(
        &rig,
        format!(
            "{{\"format\": \"psdcal-rig\", \"version\": 1, \"sensors\": [\n{}\n]}}\n",
            entries.join(",\n")
        ),
    )
    .unwrap();
    (rig, out)
}

#[test]
fn locate_with_a_rig_of_three_sensors() {
    let dir = tempfile::tempdir().unwrap();
    let (rig, sensors) = write_rig(dir.path());
    let emitters = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(120.0, -80.0, 200.0),
        Vector3::new(-60.0, 90.0, -100.0),
    ];
    let mut text = String::from("emitter,sensor,vx1,vx2,vy1,vy2\n");
    for (k, e) in emitters.iter().enumerate() {
        for (id, model, pose) in &sensors {
            let p = pose.inverse().transform(e);
            let m = measured_from_ray(
                &psdcal_model::Model::standard(model),
                &Vector2::new(p.x / p.z, p.y / p.z),
            )
            .unwrap();
            let a = electrode_currents(&PsdGeometry::default(), &m, 1.0);
            text.push_str(&format!(
                "E{k},{id},{},{},{},{}\n",
                a.vx1, a.vx2, a.vy1, a.vy2
            ));
        }
    }
    // One emitter seen by a single sensor.
    text.push_str("lonely,left,1,1,1,1\n");
    let points = dir.path().join("rig_points.csv");
    fs::write(&points, text).unwrap();
    let out = dir.path().join("emitters.csv");
    let (summary, err) = run_ok(&[
        "locate",
        "--rig",
        rig.to_str().unwrap(),
        "-p",
        points.to_str().unwrap(),
        "--point-sigma",
        "0.001",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        summary.contains("locate: 4 emitters of") && summary.contains("3 ok, 1 too_few_sensors"),
        "{summary}"
    );
    assert!(err.contains("emitter 'lonely' (line 11)"), "{err}");
    let (header, rows) = table(&fs::read_to_string(&out).unwrap());
    assert_eq!(
        &header[..5],
        [
            "emitter",
            "sensors",
            "x_world_mm",
            "y_world_mm",
            "z_world_mm"
        ]
    );
    for (row, e) in rows.iter().zip(&emitters) {
        assert_eq!(row[1], "left;right;back");
        let got = Vector3::new(
            value(&header, row, "x_world_mm"),
            value(&header, row, "y_world_mm"),
            value(&header, row, "z_world_mm"),
        );
        assert!((got - e).norm() < 1e-9, "{got:?} vs {e:?}");
        assert!(value(&header, row, "sigma_position_mm") > 0.0);
        assert!(value(&header, row, "ray_angle_deg") > 40.0);
    }
    assert_eq!(rows[3][0], "lonely");
    assert_eq!(rows[3].last().unwrap(), "too_few_sensors");
    assert_eq!(rows[3][column(&header, "x_world_mm")], "");
}

#[test]
fn malformed_rigs_name_the_file_and_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let (rig, _) = write_rig(dir.path());
    let points = dir.path().join("p.csv");
    fs::write(
        &points,
        "emitter,sensor,x_mm,y_mm\n1,left,0,0\n1,right,0,0\n",
    )
    .unwrap();
    let good = fs::read_to_string(&rig).unwrap();
    let cases = [
        (
            good.replacen("\"t_mm\": [", "\"t_mm\": [1, ", 1),
            "sensors[0].world_from_sensor.t_mm",
        ),
        (
            good.replacen("\"id\": \"right\"", "\"id\": \"left\"", 1),
            "sensors[1].id",
        ),
        (
            good.replacen("psdcal-rig", "psdcal-calibration", 1),
            "format",
        ),
    ];
    for (text, field) in cases {
        fs::write(&rig, &text).unwrap();
        let out = psdcal([
            "locate",
            "--rig",
            rig.to_str().unwrap(),
            "-p",
            points.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(1), "{field}");
        let err = stderr(&out);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.starts_with(&format!("error: {}: field '{field}': ", rig.display())),
            "{err}"
        );
        assert!(
            err.contains("; correct that field of the rig file"),
            "{err}"
        );
    }
    // A calibration the rig names but that is missing: the error names it.
    fs::write(&rig, good.replacen("cal/back.json", "cal/none.json", 1)).unwrap();
    let out = psdcal([
        "locate",
        "--rig",
        rig.to_str().unwrap(),
        "-p",
        points.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("none.json: cannot read the file"),
        "{}",
        stderr(&out)
    );
    // A sensor the rig does not have: the error names the line.
    fs::write(&rig, &good).unwrap();
    fs::write(
        &points,
        "emitter,sensor,x_mm,y_mm\n1,left,0,0\n1,front,0,0\n",
    )
    .unwrap();
    let out = psdcal([
        "locate",
        "--rig",
        rig.to_str().unwrap(),
        "-p",
        points.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("p.csv:3: sensor 'front' is not in the rig"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn map_writes_the_full_model_grid() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map.csv");
    let (text, _) = run_ok(&[
        "map",
        "--lens",
        "2",
        "--error",
        "f=0.2,cx=0.05",
        "--error",
        "k1=-1e-3",
        "--grid",
        "7",
        "--paper",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        text.contains("7 x 7 grid over 9 x 9 mm, plane at 5000 mm"),
        "{text}"
    );
    assert!(text.contains("49 ok"), "{text}");
    let (header, rows) = table(&fs::read_to_string(&out).unwrap());
    assert_eq!(rows.len(), 49);
    assert!(header.contains(&"paper_aoa_error_x_deg".to_string()));
    let errors =
        ParameterErrors::new(vec![(Param::F, 0.2), (Param::Cx, 0.05), (Param::K1, -1e-3)]).unwrap();
    let map = error_map(
        &SensorModel::paper_lens2(),
        &PsdGeometry::default(),
        &ErrorSource::Parameters(errors),
        &MapOptions {
            grid: 7,
            distance_mm: 5000.0,
            paper_form: true,
        },
    )
    .unwrap();
    for (row, cell) in rows.iter().zip(&map.cells) {
        let v = cell.values.as_ref().unwrap();
        assert_eq!(value(&header, row, "x_mm"), cell.measured.x);
        assert_eq!(
            value(&header, row, "aoa_error_deg"),
            v.aoa_error_total.to_degrees()
        );
        assert_eq!(
            value(&header, row, "position_error_mm"),
            v.position_error_total
        );
    }
    // From a calibration's covariance.
    let cal = valid("calibration.json");
    let (text, _) = run_ok(&[
        "--json",
        "map",
        "-c",
        cal.to_str().unwrap(),
        "--k-sigma",
        "2",
        "--grid",
        "5",
        "--out",
        out.to_str().unwrap(),
    ]);
    let json: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(json["rows"]["answered"], 25);
    assert!(json["max_position_error_mm"].as_f64().unwrap() > 0.0);
}

#[test]
fn help_and_usage_errors() {
    for command in ["aoa", "locate", "map"] {
        let (text, _) = run_ok(&[command, "--help"]);
        assert!(text.contains("Example"), "{command}: {text}");
    }
    let (text, _) = run_ok(&["--help"]);
    assert!(text.contains("psdcal locate --calibration"), "{text}");
    for args in [
        vec!["locate", "-c", "c.json", "-p", "p.csv"],
        vec!["locate", "-p", "p.csv", "--distance", "-5"],
        vec!["map", "--lens", "1"],
        vec!["aoa", "-p", "p.csv"],
    ] {
        let out = psdcal(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
    }
}
