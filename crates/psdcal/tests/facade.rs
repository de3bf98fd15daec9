//! The facade end to end on the shipped example (noise-free lens 2): a data
//! set from files and the same from memory calibrate alike; the record
//! round-trips through calibration.json version 2 into the same sensor;
//! the residual table agrees with the fit.

use std::path::PathBuf;

use psdcal::{
    calibrate, sensor_of, CalibrationOptions, DataSet, DataSetFiles, LoadOptions, LoadedSensor,
    LocateOptions, Measurement, MemoryPoints, PointSource,
};
use psdcal_io::{Observations, Template};

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/example")
        .join(name)
}

fn files() -> DataSetFiles {
    DataSetFiles {
        template: example("template.csv"),
        points: PointSource::Observations(example("observations.csv")),
        gains: None,
    }
}

#[test]
fn files_and_memory_give_the_same_calibration() {
    let from_files = DataSet::from_files(&files(), &LoadOptions::default()).unwrap();
    assert_eq!(from_files.inputs.0.len(), 2);
    let template = Template::read(example("template.csv")).unwrap();
    let observations = Observations::read(example("observations.csv")).unwrap();
    let in_memory = DataSet::from_memory(
        template,
        MemoryPoints::Observations(observations),
        &LoadOptions::default(),
    )
    .unwrap();
    assert!(in_memory.inputs.0.is_empty());
    let options = CalibrationOptions::default();
    let a = calibrate(&from_files, &options).unwrap();
    let b = calibrate(&in_memory, &options).unwrap();
    assert_eq!(a.record.to_model(), b.record.to_model());
    assert_eq!(a.report.residual_mm2, b.report.residual_mm2);
}

#[test]
fn the_record_round_trips_and_the_residuals_agree() {
    let set = DataSet::from_files(&files(), &LoadOptions::default()).unwrap();
    let mut calibrated = calibrate(&set, &CalibrationOptions::default()).unwrap();
    calibrated.set_command("psdcal calibrate (test)");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("calibration.json");
    let residuals = dir.path().join("residuals.csv");
    calibrated.write(&set, &out, Some(&residuals)).unwrap();
    let loaded = LoadedSensor::read(&out).unwrap();
    assert_eq!(loaded.record, calibrated.record);
    let provenance = loaded.record.provenance.as_ref().unwrap();
    assert_eq!(provenance.command, "psdcal calibrate (test)");
    assert_eq!(
        provenance.options["free"],
        serde_json::json!(["f", "cx", "cy", "k1", "k2"])
    );
    // Every point of every image has residuals, and their RMS is the fit's.
    let table = calibrated.residuals(&set);
    let points: usize = table.images.iter().map(|i| i.points).sum();
    assert_eq!(points, calibrated.report.points);
    for (image, row) in table.images.iter().zip(&calibrated.report.per_image) {
        let (t, s) = image.rms();
        assert!((t.unwrap() - row.rms_template_mm).abs() <= 1e-12);
        assert!((s.unwrap() - row.rms_image_mm).abs() <= 1e-12);
    }
    let csv = std::fs::read_to_string(residuals).unwrap();
    assert_eq!(csv.lines().count(), 1 + points);
    // The same angles from the record in memory and from the file.
    let m = Measurement::Point(nalgebra::Vector2::new(1.0, -0.5));
    let o = LocateOptions::default();
    let from_record = sensor_of(&calibrated.record).unwrap().aoa(&m, &o).unwrap();
    let from_file = loaded.sensor.aoa(&m, &o).unwrap();
    assert_eq!(from_record.aoa.alpha, from_file.aoa.alpha);
}

#[test]
fn options_that_cannot_work_are_typed_errors() {
    let set = DataSet::from_files(&files(), &LoadOptions::default()).unwrap();
    let options = CalibrationOptions {
        fit_gains: true,
        ..CalibrationOptions::default()
    };
    assert!(matches!(
        calibrate(&set, &options),
        Err(psdcal::Error::Options(_))
    ));
}

#[test]
fn the_warnings_alone_are_the_summarys() {
    // Lens terms the regression set cannot separate: warnings and a
    // diagnostic, which `psdcal -q calibrate` prints without the summary.
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/l1-wrong-minimum");
    let files = DataSetFiles {
        template: dir.join("template.csv"),
        points: PointSource::Observations(dir.join("observations.csv")),
        gains: None,
    };
    let set = DataSet::from_files(&files, &LoadOptions::default()).unwrap();
    use psdcal_model::Param::*;
    let options = CalibrationOptions {
        free: vec![F, Cx, Cy, K1, K2, K3, P1, P2],
        choice: psdcal::ModelChoice::Given,
        ..CalibrationOptions::default()
    };
    let calibrated = calibrate(&set, &options).unwrap();
    let out = std::path::Path::new("calibration.json");
    let summary = calibrated.summary(out, None).unwrap();
    assert!(summary.warnings.len() >= 2, "{:?}", summary.warnings);
    assert_eq!(calibrated.warnings(), summary.warnings);
}

#[test]
fn a_data_set_of_files_and_rows_lists_only_its_files_with_their_hashes() {
    use psdcal::arrays::{data_set, PointsInput, Rows, TableInput};
    let observations = Observations::read(example("observations.csv")).unwrap();
    let ids = |s: &str| s.parse::<f64>().unwrap();
    let values: Vec<f64> = observations
        .rows
        .iter()
        .flat_map(|o| [ids(&o.image), ids(&o.led), o.x_mm, o.y_mm])
        .collect();
    let rows = Rows {
        name: "observations array",
        values: &values,
        columns: 4,
    };
    let template = example("template.csv");
    let set = data_set(
        &TableInput::File(template.clone()),
        &PointsInput::Observations(TableInput::Rows(rows)),
        None,
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(set.inputs.0.len(), 1);
    assert_eq!(set.inputs.0[0].path, template.display().to_string());
    assert_eq!(
        set.inputs.0[0].sha256,
        psdcal::sha256_hex(&std::fs::read(&template).unwrap())
    );
    // The same data as two files: both listed, in the order read.
    let both = data_set(
        &TableInput::File(template.clone()),
        &PointsInput::Observations(TableInput::File(example("observations.csv"))),
        None,
        &LoadOptions::default(),
    )
    .unwrap();
    let paths: Vec<&str> = both.inputs.0.iter().map(|i| i.path.as_str()).collect();
    assert_eq!(
        paths,
        [
            template.display().to_string(),
            example("observations.csv").display().to_string()
        ]
    );
    assert_eq!(set.template, both.template);
}

#[test]
fn the_calibration_folder_is_created_as_simulate_creates_its_own() {
    let set = DataSet::from_files(&files(), &LoadOptions::default()).unwrap();
    let calibrated = calibrate(&set, &CalibrationOptions::default()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out/new/calibration.json");
    let residuals = dir.path().join("out/other/residuals.csv");
    calibrated.write(&set, &out, Some(&residuals)).unwrap();
    assert_eq!(LoadedSensor::read(&out).unwrap().record, calibrated.record);
    assert!(residuals.exists());
}
