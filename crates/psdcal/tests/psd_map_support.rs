//! The acceptance experiment of the PSD map (docs/model.md §8.3), shared by
//! `tests/psd_map.rs` (a few seeds) and `examples/psd_map_acceptance.rs`
//! (ten): per seed, a simulated data set of lens 2 at 40 dB with 12 images
//! and the PSD's non-radial non-linearity, calibrated (a) with the map of a
//! simulated 0.25 mm raster scan (37 × 37, stage σ 0.3 µm, 50 dB) held
//! fixed, (b) with `l1` freed instead, and (c) the same data set without
//! any non-linearity (the same seed: the same poses and noise), calibrated
//! plainly. Each calibration is judged by its RMS angle error over 9 × 9
//! held-out directions (80 % of the sensor), measured through the true
//! non-linearity without noise, answered from the calibration record alone
//! (`psdcal::sensor_of`), against the true ray.

#![allow(dead_code)]

use std::path::Path;

use nalgebra::Vector2;
use psdcal::{
    calibrate, psd_map_from_scan, sensor_of, simulate_files, simulate_scan_file,
    CalibrationOptions, DataSet, DataSetFiles, LoadOptions, LocateOptions, Measurement, Param,
    PointSource, PsdGeometry, PsdMapModel, PsdMapRequest, ScanRequest, SimulateRequest,
    DEFAULT_RECORD_CYCLES,
};
use psdcal_model::SensorModel;
use psdcal_sim::{Lens, PsdNonlinearity, TemplateKind};

/// One seed's angle errors (rad) and the map's error against the truth.
#[derive(Debug, Clone, Copy)]
pub struct SeedErrors {
    /// Calibrated with the map.
    pub map: f64,
    /// Calibrated with `l1` freed.
    pub l1: f64,
    /// The same data without non-linearity.
    pub clean: f64,
    /// RMS of the map's error against the true field over the scan's
    /// interior, mm.
    pub map_error_mm: f64,
    /// The scan's noise per axis (√(σx² + σy²)/√2), mm.
    pub scan_noise_mm: f64,
}

fn data_set(dir: &Path, seed: u64, nonlinearity: bool) -> DataSet {
    simulate_files(&SimulateRequest {
        lens: Lens::Two,
        snr_db: Some(40.0),
        imbalance: false,
        psd_distortion: false,
        psd_nonlinearity: nonlinearity,
        images: 12,
        template: TemplateKind::Scatter14,
        record_cycles: DEFAULT_RECORD_CYCLES,
        seed,
        out: dir.to_path_buf(),
    })
    .unwrap();
    DataSet::from_files(
        &DataSetFiles {
            template: dir.join("template.csv"),
            points: PointSource::Observations(dir.join("observations.csv")),
            gains: None,
        },
        &LoadOptions::default(),
    )
    .unwrap()
}

/// The RMS angle error of a calibration (module documentation), rad.
fn aoa_error(record: &psdcal::Calibration, nonlinearity: bool) -> f64 {
    let truth = SensorModel::paper_lens2();
    let geometry = PsdGeometry::default();
    let nl = PsdNonlinearity::new(geometry);
    let sensor = sensor_of(record).unwrap();
    let (mut sum, mut n) = (0.0, 0);
    for i in 0..9 {
        for j in 0..9 {
            let ideal = Vector2::new(
                0.4 * geometry.lx * (i as f64 / 4.0 - 1.0),
                0.4 * geometry.ly * (j as f64 / 4.0 - 1.0),
            );
            let spot = truth.distort(&ideal).unwrap();
            let m = if nonlinearity {
                nl.reported(&spot)
            } else {
                spot
            };
            let est = sensor
                .aoa(&Measurement::Point(m), &LocateOptions::default())
                .unwrap();
            let e = est.aoa.direction.into_inner();
            let t = truth.ray_direction(&ideal).into_inner();
            let angle = e.cross(&t).norm().atan2(e.dot(&t));
            sum += angle * angle;
            n += 1;
        }
    }
    (sum / n as f64).sqrt()
}

/// The experiment for one seed; `amplitudes`: fit the map from the scan's
/// amplitude form.
pub fn run_seed(dir: &Path, seed: u64, amplitudes: bool) -> SeedErrors {
    let scan = dir.join(format!("scan{seed}.csv"));
    let scanned = simulate_scan_file(&ScanRequest {
        step_mm: 0.25,
        stage_sigma_um: 0.3,
        snr_db: Some(50.0),
        nonlinearity: true,
        geometry: PsdGeometry::default(),
        seed: 1000 + seed,
        out: scan.clone(),
    })
    .unwrap();
    if amplitudes {
        let stage: Vec<_> = scanned.samples.iter().map(|s| s.stage).collect();
        let amps: Vec<_> = scanned.samples.iter().map(|s| s.amplitudes).collect();
        psdcal_io::write_scan(&scan, &stage, None, Some(&amps)).unwrap();
    }
    let fitted = psd_map_from_scan(&PsdMapRequest {
        scan: scan.clone(),
        model: PsdMapModel::Auto,
        geometry: PsdGeometry::default(),
        seed,
        command: String::new(),
    })
    .unwrap();
    assert_eq!(fitted.file.fit.from_amplitudes, amplitudes);
    let map_path = dir.join(format!("psd_map{seed}.json"));
    fitted.write(&map_path).unwrap();
    // The map against the true field (measured → spot) inside the scan.
    let nl = PsdNonlinearity::new(PsdGeometry::default());
    let (mut s, mut k) = (0.0, 0);
    for i in 0..41 {
        for j in 0..41 {
            let m = Vector2::new(-4.3 + 8.6 * i as f64 / 40.0, -4.3 + 8.6 * j as f64 / 40.0);
            let truth = nl.spot(&m).unwrap() - m;
            let d = fitted.fit.map.displacement(&fitted.fit.block, &m);
            s += (d - truth).norm_squared();
            k += 1;
        }
    }
    let map_error_mm = (s / k as f64).sqrt();

    let noisy = data_set(&dir.join(format!("nl{seed}")), seed, true);
    let with_map = CalibrationOptions {
        psd_map: Some(map_path),
        ..CalibrationOptions::default()
    };
    let map = aoa_error(&calibrate(&noisy, &with_map).unwrap().record, true);
    let free_l1 = CalibrationOptions {
        free: vec![
            Param::F,
            Param::Cx,
            Param::Cy,
            Param::K1,
            Param::K2,
            Param::L1,
        ],
        ..CalibrationOptions::default()
    };
    let l1 = aoa_error(&calibrate(&noisy, &free_l1).unwrap().record, true);
    let clean_set = data_set(&dir.join(format!("clean{seed}")), seed, false);
    let clean = aoa_error(
        &calibrate(&clean_set, &CalibrationOptions::default())
            .unwrap()
            .record,
        false,
    );
    SeedErrors {
        map,
        l1,
        clean,
        map_error_mm,
        scan_noise_mm: fitted.fit.sigma_mm.norm() / 2f64.sqrt(),
    }
}

/// RMS over seeds of one field.
pub fn pooled(errors: &[SeedErrors], field: fn(&SeedErrors) -> f64) -> f64 {
    (errors.iter().map(|e| field(e).powi(2)).sum::<f64>() / errors.len() as f64).sqrt()
}
