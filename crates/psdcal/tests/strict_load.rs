//! A calibration file is checked on reading as strictly as a fresh
//! calibration (docs/formats.md, "calibration.json: checks on reading"):
//! the hand edits that used to answer `ok` with nonsense are refused with
//! one line naming the file and the field, and the valid region is
//! recomputed from the parameters, never taken from the file.

use std::path::{Path, PathBuf};

use psdcal::{calibrate, CalibrationOptions, DataSet, DataSetFiles, LoadOptions, LoadedSensor};
use psdcal_model::{PsdGeometry, SensorModel, ValidRegion};
use serde_json::Value;

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/example")
        .join(name)
}

/// The example data's calibration.json (noise-free lens 2), as JSON.
fn calibration_json(dir: &Path) -> Value {
    let files = DataSetFiles {
        template: example("template.csv"),
        points: psdcal::PointSource::Observations(example("observations.csv")),
        gains: None,
    };
    let set = DataSet::from_files(&files, &LoadOptions::default()).unwrap();
    let calibrated = calibrate(&set, &CalibrationOptions::default()).unwrap();
    let out = dir.join("calibration.json");
    calibrated.write(&set, &out, None).unwrap();
    serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap()
}

/// Sets parameter `name` in the flat map and in its stage.
fn set(json: &mut Value, name: &str, value: f64) {
    json["parameters"][name] = value.into();
    for stage in json["stages"].as_array_mut().unwrap() {
        if stage["parameters"].get(name).is_some() {
            stage["parameters"][name] = value.into();
        }
    }
}

/// Reads `json` written to `dir/name`: the sensor, or the error's text.
fn read(dir: &Path, name: &str, json: &Value) -> Result<LoadedSensor, String> {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string_pretty(json).unwrap()).unwrap();
    LoadedSensor::read(&path).map_err(|e| e.to_string())
}

fn refused(dir: &Path, name: &str, json: &Value, expected: &str) {
    let e = read(dir, name, json).map(|_| ()).unwrap_err();
    assert!(
        e.starts_with(&format!("{}: ", dir.join(name).display())),
        "{e}"
    );
    assert!(e.contains(expected), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
}

#[test]
fn the_probed_hand_edits_are_refused_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let good = calibration_json(dir.path());
    read(dir.path(), "good.json", &good).unwrap();

    // skew = 1e300 answered alpha −90°, a zero ray and σ 0, status ok.
    let mut j = good.clone();
    set(&mut j, "skew", 1e300);
    refused(
        dir.path(),
        "skew.json",
        &j,
        "|intrinsics.skew| is 1e300, not below f",
    );

    // f = 1e-300 was accepted.
    let mut j = good.clone();
    set(&mut j, "f", 1e-300);
    refused(
        dir.path(),
        "f.json",
        &j,
        "intrinsics.f_mm is 1e-300, below the plausible 0.01",
    );

    // k1 = 1e300 with the old valid_region: the region was trusted.
    let mut j = good.clone();
    set(&mut j, "k1", 1e300);
    assert!(j.get("valid_region").is_some());
    refused(
        dir.path(),
        "k1.json",
        &j,
        "distortion.k1 = 1e300: the distortion correction folds",
    );

    // σ × 1e150 (std and covariance alike) gave ok rows with blank σ cells.
    let mut j = good.clone();
    for (_, v) in j["std"].as_object_mut().unwrap() {
        *v = (v.as_f64().unwrap() * 1e150).into();
    }
    for row in j["covariance"]["matrix"].as_array_mut().unwrap() {
        for v in row.as_array_mut().unwrap() {
            *v = (v.as_f64().unwrap() * 1e300).into();
        }
    }
    refused(
        dir.path(),
        "sigma.json",
        &j,
        "covariance: the angle sigma it gives at",
    );

    // σ × 1e150 in std alone: the printed σ and the propagated one disagree.
    let mut j = good.clone();
    let f = j["std"]["f"].as_f64().unwrap();
    j["std"]["f"] = (f * 1e150).into();
    refused(dir.path(), "std.json", &j, "std.f is");
}

#[test]
fn the_valid_region_is_recomputed_not_read() {
    let dir = tempfile::tempdir().unwrap();
    let mut j = calibration_json(dir.path());
    let stored = j["valid_region"].clone();
    // A pin-cushion correction that folds about 4 mm from the optical
    // centre, with the old region (whole active area) left in the file.
    set(&mut j, "k1", -0.02);
    let loaded = read(dir.path(), "k1.json", &j).unwrap();
    let region = &loaded.sensor.valid_region;
    assert!(stored["whole_active_area"].as_bool().unwrap());
    assert!(!region.whole_active_area());
    // The region of the edited parameters, computed here from the model.
    let model: SensorModel = loaded.record.to_model();
    assert_eq!(model.distortion.k1, -0.02);
    let expected = ValidRegion::of_sensor_model(&model, &PsdGeometry { lx: 9.0, ly: 9.0 });
    assert_eq!(region.radii(), expected.radii());
    // Where 1 + 3 k1 r² = 0 along a ray of the lens's radial term (k2 = 3e-5
    // shifts it a little): r ≈ 4.08 mm.
    let nearest = region.nearest_fold_mm().unwrap();
    assert!((3.9..4.2).contains(&nearest), "{nearest}");
    // And a file without the region answers the same.
    j.as_object_mut().unwrap().remove("valid_region");
    let without = read(dir.path(), "k1-without.json", &j).unwrap();
    assert_eq!(without.sensor.valid_region, *region);
}

#[test]
fn a_row_whose_answer_is_not_finite_is_never_ok() {
    let dir = tempfile::tempdir().unwrap();
    let j = calibration_json(dir.path());
    let cal = dir.path().join("c.json");
    std::fs::write(&cal, serde_json::to_string(&j).unwrap()).unwrap();
    // A point whose amplitudes are finite but overflow on the way (the
    // impact point of amplitudes near f64::MAX is not finite).
    let points = dir.path().join("points.csv");
    std::fs::write(
        &points,
        "vx1,vx2,vy1,vy2\n1,1.2,1,0.9\n1e308,1.7e308,1e308,1.7e308\n",
    )
    .unwrap();
    let out = dir.path().join("aoa.csv");
    psdcal::aoa_table(&cal, &points, None, Some(&out), Default::default()).unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    for line in text.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        if cells.last() == Some(&"ok") {
            assert!(cells.iter().all(|c| !c.is_empty()), "{line}");
        }
    }
}
