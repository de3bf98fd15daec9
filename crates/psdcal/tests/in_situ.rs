//! `calibrate_in_situ` end to end on files (docs/model.md §8.4): a
//! simulated room written as template.csv (with Z_mm) and observations.csv,
//! calibrated, calibration.json read back, the poses file read as a rig;
//! the position Jacobian against central differences; refusals.

use std::fmt::Write as _;
use std::path::Path;

use nalgebra::Vector3;
use psdcal::{
    calibrate_in_situ, position_with_jacobian, DataSet, DataSetFiles, LoadOptions, PointSource,
};
use psdcal_io::{read_calibration, RigFile};
use psdcal_model::Pose;
use psdcal_sim::insitu::{InSituOptions, InSituScene};
use rand::SeedableRng;

fn write_scene(dir: &Path, scene: &InSituScene, flat: bool) -> DataSetFiles {
    let mut t = String::from("led,X_mm,Y_mm,Z_mm\n");
    for (k, p) in scene.surveyed.iter().enumerate() {
        let z = if flat { 0.0 } else { p.z };
        writeln!(t, "e{},{},{},{}", k + 1, p.x, p.y, z).unwrap();
    }
    let mut o = String::from("image,led,x_mm,y_mm\n");
    for (i, seen) in scene.observations.iter().enumerate() {
        for (k, m) in seen {
            writeln!(o, "o{},e{},{},{}", i + 1, k + 1, m.x, m.y).unwrap();
        }
    }
    std::fs::write(dir.join("emitters.csv"), t).unwrap();
    std::fs::write(dir.join("obs.csv"), o).unwrap();
    DataSetFiles {
        template: dir.join("emitters.csv"),
        points: PointSource::Observations(dir.join("obs.csv")),
        gains: None,
    }
}

#[test]
fn files_to_calibration_and_rig_poses() {
    let options = InSituOptions {
        orientations: 2,
        ..InSituOptions::default()
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(42);
    let scene = InSituScene::draw(&options, &mut rng).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let files = write_scene(dir.path(), &scene, false);
    let set = DataSet::from_files(&files, &LoadOptions::default()).unwrap();
    let insitu = calibrate_in_situ(&set, options.survey_sigma_mm).unwrap();
    let cal = dir.path().join("calibration.json");
    let poses = dir.path().join("sensor_pose.json");
    insitu.write(&cal, Some(&poses)).unwrap();
    let record = read_calibration(&cal).unwrap();
    let f = record.intrinsics.f_mm;
    let sf = insitu.result.covariance.std("f").unwrap();
    assert!((f - 8.0).abs() < 5.0 * sf, "f = {f} ± {sf}");
    assert_eq!(record.images.len(), 2);
    let text = std::fs::read_to_string(&poses).unwrap();
    let rig = RigFile::from_json_str("sensor_pose.json", &text, dir.path()).unwrap();
    assert_eq!(rig.sensors.len(), 2);
    assert_eq!(rig.sensors[0].calibration, "calibration.json");
    for (k, s) in rig.sensors.iter().enumerate() {
        let truth = scene.room_from_sensor[k];
        let p = &insitu.poses[k];
        let sd = p.position_covariance.diagonal().map(f64::sqrt);
        let err = s.world_from_sensor.t - truth.t;
        for a in 0..3 {
            assert!(
                err[a].abs() < 5.0 * sd[a],
                "axis {a}: {} vs σ {}",
                err[a],
                sd[a]
            );
        }
        assert!((p.position_mm - s.world_from_sensor.t).norm() < 1e-6);
    }
    assert!(insitu.text().contains("orientation 'o1'"));
    assert!(insitu.json()["poses"].as_array().unwrap().len() == 2);
    // A clean scene: no diagnostics, the linearity check ran and holds.
    assert!(record.diagnostics.is_empty(), "{:?}", record.diagnostics);
    let json = insitu.json();
    assert_eq!(json["diagnostics"].as_array().map(Vec::len), Some(0));
    assert_eq!(json["linearity"]["verdict"]["verdict"], "reliable");
    assert_eq!(
        json["linearity"]["parameters"].as_array().map(Vec::len),
        Some(5)
    );
}

/// The impact point a PSD with relative channel gains `(x2, y1, y2)` (x1 = 1)
/// reports for light at `m` (bilinear current shares, the pin-cushion
/// formula on the amplified signals; a 9 × 9 mm area).
fn through_gains(m: &nalgebra::Vector2<f64>, g: [f64; 3]) -> nalgebra::Vector2<f64> {
    let (u, v) = (m.x / 4.5, m.y / 4.5);
    let x1 = (1.0 - u) * (1.0 - v);
    let x2 = (1.0 + u) * (1.0 + v) * g[0];
    let y1 = (1.0 + u) * (1.0 - v) * g[1];
    let y2 = (1.0 - u) * (1.0 + v) * g[2];
    let s = x1 + x2 + y1 + y2;
    nalgebra::Vector2::new(
        4.5 * ((x2 + y1) - (x1 + y2)) / s,
        4.5 * ((x2 + y2) - (x1 + y1)) / s,
    )
}

#[test]
fn unequal_gains_are_diagnosed_stored_and_warned() {
    let options = InSituOptions {
        orientations: 3,
        emitters: 24,
        survey_sigma_mm: 0.5,
        ..InSituOptions::default()
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut scene = InSituScene::draw(&options, &mut rng).unwrap();
    for seen in &mut scene.observations {
        for (_, m) in seen.iter_mut() {
            *m = through_gains(m, [1.04, 0.96, 1.03]);
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let files = write_scene(dir.path(), &scene, false);
    let set = DataSet::from_files(&files, &LoadOptions::default()).unwrap();
    let insitu = calibrate_in_situ(&set, options.survey_sigma_mm).unwrap();
    let cal = dir.path().join("calibration.json");
    insitu.write(&cal, None).unwrap();
    let record = read_calibration(&cal).unwrap();
    let codes: Vec<_> = record.diagnostics.iter().map(|d| d.code).collect();
    assert!(
        codes.contains(&psdcal_model::DiagnosticCode::GainImbalanceSuspected),
        "{:?}",
        record.diagnostics
    );
    let summary = insitu.summary(&cal, None);
    assert!(summary
        .warnings
        .iter()
        .any(|w| w.contains("unequal channel gains")));
    assert_eq!(
        summary.json["diagnostics"][0]["code"],
        "gain_imbalance_suspected"
    );
}

#[test]
fn one_orientation_is_no_rig_and_the_reader_says_what_to_do() {
    let options = InSituOptions::default();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let scene = InSituScene::draw(&options, &mut rng).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let files = write_scene(dir.path(), &scene, false);
    let set = DataSet::from_files(&files, &LoadOptions::default()).unwrap();
    let insitu = calibrate_in_situ(&set, options.survey_sigma_mm).unwrap();
    let (cal, poses) = (dir.path().join("c.json"), dir.path().join("pose.json"));
    insitu.write(&cal, Some(&poses)).unwrap();
    let text = std::fs::read_to_string(&poses).unwrap();
    let e = RigFile::from_json_str("pose.json", &text, dir.path())
        .unwrap_err()
        .to_string();
    assert!(e.contains("1 sensor(s)") && e.contains("at least 2"), "{e}");
    assert!(e.contains("--poses-out") && e.contains("psdcal aoa"), "{e}");
    // Two sensors' entries in one file make a rig.
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut second = value["sensors"][0].clone();
    second["id"] = "other".into();
    value["sensors"].as_array_mut().unwrap().push(second);
    let rig = RigFile::from_json_str("rig.json", &value.to_string(), dir.path()).unwrap();
    assert_eq!(rig.sensors.len(), 2);
}

#[test]
fn position_jacobian_matches_central_differences() {
    let pose = Pose::new(
        Vector3::new(0.3, -1.2, 2.0),
        Vector3::new(400.0, -900.0, 2500.0),
    );
    let (c, j) = position_with_jacobian(&pose);
    assert!((c - pose.inverse().t).norm() < 1e-9);
    for k in 0..6 {
        let h = if k < 3 { 1e-6 } else { 1e-3 };
        let at = |s: f64| {
            let mut a = pose.to_array();
            a[k] += s;
            Pose::from_array(&a).inverse().t
        };
        let fd = (at(h) - at(-h)) / (2.0 * h);
        assert!(
            (fd - j.column(k)).norm() < 1e-5 * fd.norm().max(1.0),
            "column {k}"
        );
    }
}

#[test]
fn planar_and_coplanar_emitters_are_refused_with_what_to_change() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let scene = InSituScene::draw(&InSituOptions::default(), &mut rng).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let files = write_scene(dir.path(), &scene, true);
    let set = DataSet::from_files(&files, &LoadOptions::default()).unwrap();
    let e = calibrate_in_situ(&set, 1.0).unwrap_err();
    let text = format!(
        "{e}: {}",
        std::error::Error::source(&e).map_or(String::new(), |s| s.to_string())
    );
    assert!(
        text.contains("coplanar") && text.contains("different depths"),
        "{text}"
    );
    std::fs::write(
        dir.path().join("emitters.csv"),
        std::fs::read_to_string(dir.path().join("emitters.csv"))
            .unwrap()
            .lines()
            .map(|l| l.rsplit_once(',').unwrap().0.to_string() + "\n")
            .collect::<String>(),
    )
    .unwrap();
    let set = DataSet::from_files(&files, &LoadOptions::default()).unwrap();
    let e = calibrate_in_situ(&set, 1.0).unwrap_err().to_string();
    assert!(
        e.contains("no Z_mm column") && e.contains("psdcal calibrate"),
        "{e}"
    );
}
