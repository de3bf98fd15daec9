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

pub use psdcal::{pooled, SeedErrors};

/// The experiment for one seed (the facade's `psd_map_seed`, in memory).
pub fn run_seed(seed: u64, amplitudes: bool) -> SeedErrors {
    psdcal::psd_map_seed(seed, amplitudes).unwrap()
}

/// The files of seed `seed`'s experiment, as the command line makes them:
/// the data set with the non-linearity in `dir/nl{seed}`, the scan
/// `dir/scan{seed}.csv` and its map `dir/psd_map{seed}.json`.
pub fn write_seed_files(dir: &Path, seed: u64) {
    use psdcal::{
        psd_map_from_scan, simulate_files, simulate_scan_file, Lens, PsdGeometry, PsdMapModel,
        PsdMapRequest, ScanRequest, SimulateRequest, TemplateKind, DEFAULT_RECORD_CYCLES,
    };
    simulate_files(&SimulateRequest {
        lens: Lens::Two,
        snr_db: Some(40.0),
        imbalance: false,
        psd_distortion: false,
        psd_nonlinearity: true,
        images: 12,
        template: TemplateKind::Scatter14,
        record_cycles: DEFAULT_RECORD_CYCLES,
        seed,
        out: dir.join(format!("nl{seed}")),
        force: false,
    })
    .unwrap();
    let scan = dir.join(format!("scan{seed}.csv"));
    simulate_scan_file(&ScanRequest {
        step_mm: 0.25,
        stage_sigma_um: 0.3,
        snr_db: Some(50.0),
        nonlinearity: true,
        geometry: PsdGeometry::default(),
        seed: 1000 + seed,
        out: scan.clone(),
    })
    .unwrap();
    psd_map_from_scan(&PsdMapRequest {
        scan,
        model: PsdMapModel::Auto,
        geometry: PsdGeometry::default(),
        seed,
        command: String::new(),
        report: None,
        limits: Default::default(),
        force: false,
    })
    .unwrap()
    .write(&dir.join(format!("psd_map{seed}.json")))
    .unwrap();
}
