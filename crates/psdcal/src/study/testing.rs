//! Test-only experiments of the study's PSD-map condition (behind the
//! `testing` feature): `calibrate --refine-psd-map` against the map held
//! fixed, for a scan of a given quality (tests/psd_map_refine in
//! psdcal-cli).

use std::path::PathBuf;

use crate::base::error::{Error, Result};
use crate::simulation::simulate_scan::ScanRequest;
use crate::study::study_psd_map::{
    aoa_error, calibrate_with, data_set, fit_map, map_error, scan_in_memory,
};
use psdcal_model::PsdGeometry;

/// A scan of [`refine_seed`]: raster step (mm), stage σ (µm), SNR (dB).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanSpec {
    /// Raster step, mm.
    pub step_mm: f64,
    /// The stage's position noise, µm.
    pub stage_sigma_um: f64,
    /// The PSD's SNR during the scan, dB.
    pub snr_db: f64,
}

/// One seed of `calibrate --refine-psd-map` against the map held fixed.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RefineErrors {
    /// RMS angle error with the map held fixed, rad.
    pub held: f64,
    /// RMS angle error with the map refined, rad.
    pub refined: f64,
    /// The scan's map against the true field (RMS), mm.
    pub held_map_error_mm: f64,
    /// The refined map against the true field (RMS), mm.
    pub refined_map_error_mm: f64,
    /// The largest σ of a map coefficient from the scan, mm.
    pub held_max_sigma_mm: f64,
    /// The largest σ of a map coefficient after refinement, mm.
    pub refined_max_sigma_mm: f64,
}

/// The data set of seed `seed` (lens 2, 40 dB, 12 images, the PSD's
/// non-linearity) calibrated with the map of a scan `scan` held fixed and
/// refined (`--refine-psd-map`): angle errors as in [`psd_map_seed`], the
/// map's error against the true field before and after, and the largest
/// coefficient σ before and after.
pub fn refine_seed(seed: u64, scan: &ScanSpec) -> Result<RefineErrors> {
    let scan = scan_in_memory(
        &ScanRequest {
            step_mm: scan.step_mm,
            stage_sigma_um: scan.stage_sigma_um,
            snr_db: Some(scan.snr_db),
            nonlinearity: true,
            geometry: PsdGeometry::default(),
            seed: 1000 + seed,
            out: PathBuf::from(format!("scan{seed}.csv")),
        },
        false,
    )?;
    let (fitted, map) = fit_map(&scan, seed)?;
    let noisy = data_set(seed, true)?;
    let held = calibrate_with(&noisy, &map, false)?;
    let refined = calibrate_with(&noisy, &map, true)?;
    let stage = refined
        .psd_map
        .as_ref()
        .ok_or_else(|| Error::Input("the refined calibration lost its map".into()))?;
    let block: Vec<f64> = stage.parameters.iter().map(|(_, v)| *v).collect();
    let (held_stage, _) = held
        .psd_map
        .as_ref()
        .ok_or_else(|| Error::Input("the calibration lost its map".into()))?
        .to_stage(held.covariance.parameters.len())
        .map_err(Error::Input)?;
    let max_sigma = |c: &psdcal_model::ParameterCovariance| {
        (0..c.len())
            .map(|i| c.matrix()[(i, i)].sqrt())
            .fold(0.0, f64::max)
    };
    let prior = held.psd_map.as_ref().map(|m| m.map_covariance(&held_stage));
    let posterior = stage.map_covariance(&held_stage);
    Ok(RefineErrors {
        held: aoa_error(&held, true)?,
        refined: aoa_error(&refined, true)?,
        held_map_error_mm: map_error(&fitted.fit.map, &fitted.fit.block)?,
        refined_map_error_mm: map_error(&fitted.fit.map, &block)?,
        held_max_sigma_mm: max_sigma(
            &prior
                .ok_or_else(|| Error::Input("no map".into()))?
                .map_err(Error::Input)?,
        ),
        refined_max_sigma_mm: max_sigma(&posterior.map_err(Error::Input)?),
    })
}
