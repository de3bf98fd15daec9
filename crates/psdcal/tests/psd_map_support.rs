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

/// The experiment for one seed (the facade's `psd_map_seed`).
pub fn run_seed(dir: &Path, seed: u64, amplitudes: bool) -> SeedErrors {
    psdcal::psd_map_seed(dir, seed, amplitudes).unwrap()
}
