//! The PSD map in use (issue 14's acceptance, docs/model.md §8.3; the
//! experiment is in `psd_map_support.rs`, ten seeds in
//! `examples/psd_map_acceptance.rs`): with the non-radial non-linearity, a
//! calibration with the scanned map answers angles within 1.2× those of the
//! same data without non-linearity and at most half those of freeing `l1`
//! (pooled over seeds), from the calibration record alone; the map reaches
//! a few tenths of a µm against the true field, below the scan's noise; the
//! amplitude form of the scan does as well. And the bad inputs.

mod psd_map_support;

use psd_map_support::{pooled, run_seed, write_seed_files};
use psdcal::{
    calibrate, CalibrationOptions, DataSet, DataSetFiles, LoadOptions, PointSource, PsdGeometry,
};

#[test]
fn the_scanned_map_restores_the_angles() {
    let errors: Vec<_> = (1..=3).map(|s| run_seed(s, false)).collect();
    let (map, l1, clean) = (
        pooled(&errors, |e| e.map),
        pooled(&errors, |e| e.l1),
        pooled(&errors, |e| e.clean),
    );
    assert!(map <= 1.2 * clean, "map {map:e} rad vs clean {clean:e} rad");
    assert!(map <= 0.5 * l1, "map {map:e} rad vs l1 freed {l1:e} rad");
    for e in &errors {
        // A few tenths of a µm, below the scan's own noise (≈ 0.37 µm).
        assert!(e.map_error_mm < 0.3e-3, "{e:?}");
        assert!(e.map_error_mm < e.scan_noise_mm, "{e:?}");
    }
    // The amplitude form of the scan: the same map quality and angles.
    let a = run_seed(4, true);
    assert!(a.map_error_mm < 0.3e-3, "{a:?}");
    assert!(a.map <= 1.2 * pooled(&[a], |e| e.clean) * 1.3, "{a:?}");
}

#[test]
fn a_map_of_another_sensor_or_a_scan_that_misses_the_data_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let e = run_seed(5, false);
    assert!(e.map.is_finite());
    write_seed_files(dir.path(), 5);
    let set = DataSet::from_files(
        &DataSetFiles {
            template: dir.path().join("nl5/template.csv"),
            points: PointSource::Observations(dir.path().join("nl5/observations.csv")),
            gains: None,
        },
        &LoadOptions {
            geometry: PsdGeometry { lx: 10.0, ly: 10.0 },
            strict: false,
            limits: Default::default(),
        },
    )
    .unwrap();
    let options = CalibrationOptions {
        psd_map: Some(dir.path().join("psd_map5.json")),
        ..CalibrationOptions::default()
    };
    let err = calibrate(&set, &options).unwrap_err().to_string();
    assert!(
        err.contains("psd_map5.json") && err.contains("9 mm × 9 mm"),
        "{err}"
    );

    // A scan of the left half only: the data's right half is outside the
    // map's hull, so the calibration is refused (outside its valid region).
    let scan = dir.path().join("scan5.csv");
    let text = std::fs::read_to_string(&scan).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let half: Vec<&str> = lines
        .filter(|l| l.split(',').next().unwrap().parse::<f64>().unwrap() <= 0.0)
        .collect();
    let half_scan = dir.path().join("half.csv");
    std::fs::write(&half_scan, format!("{header}\n{}\n", half.join("\n"))).unwrap();
    let fitted = psdcal::psd_map_from_scan(&psdcal::PsdMapRequest {
        scan: half_scan,
        model: psdcal::PsdMapModel::Auto,
        geometry: PsdGeometry::default(),
        seed: 0,
        command: String::new(),
        report: None,
        limits: Default::default(),
        force: false,
    })
    .unwrap();
    let half_map = dir.path().join("half.json");
    fitted.write(&half_map).unwrap();
    let set = DataSet::from_files(
        &DataSetFiles {
            template: dir.path().join("nl5/template.csv"),
            points: PointSource::Observations(dir.path().join("nl5/observations.csv")),
            gains: None,
        },
        &LoadOptions::default(),
    )
    .unwrap();
    let options = CalibrationOptions {
        psd_map: Some(half_map),
        ..CalibrationOptions::default()
    };
    let err = calibrate(&set, &options).unwrap_err();
    assert!(
        matches!(err, psdcal::Error::DataOutsidePsdMap { .. })
            && err.to_string().contains("half.json"),
        "{err}"
    );
}
