//! The study's PSD-map condition (docs/model.md §8.3; EXPERIMENTS.md): per
//! seed, a simulated data set of lens 2 at 40 dB with 12 images and the
//! PSD's non-radial non-linearity, calibrated (a) with the map of a
//! simulated 0.25 mm raster scan (37 × 37, stage σ 0.3 µm, 50 dB) held
//! fixed, (b) with `l1` freed instead, and (c) the same data set without
//! any non-linearity (the same seed: the same poses and noise), calibrated
//! plainly; and (d) with the same map refined (`--refine-psd-map`). Each calibration is judged by its RMS angle error over 9 × 9
//! held-out directions (80 % of the sensor), measured through the true
//! non-linearity without noise, answered from the calibration record alone
//! (`sensor_of`), against the true ray: `e = atan2(|d̂ × t̂|, d̂ · t̂)`,
//! `RMS = √(Σ e² / 81)`. Seeds pool by the RMS of their RMS errors. The
//! map's own error is the RMS of `d(m) − (spot(m) − m)` over a 41 × 41 grid
//! inside the scan, next to the scan's noise `√((σx² + σy²)/2)`.

use std::path::PathBuf;

use nalgebra::Vector2;
use psdcal_io::{
    Calibration, Led, Observation, Observations, Scan, ScanReading, ScanRow, Template,
};
use psdcal_locate::{LocateOptions, Measurement};
use psdcal_model::{Model, Param, PsdGeometry, SensorModel};
use psdcal_sim::{Lens, PsdNonlinearity, TemplateKind};

use crate::answer::loaded_sensor::sensor_of;
use crate::base::error::{Error, Result};
use crate::base::options::CalibrationOptions;
use crate::base::provenance::InputHashes;
use crate::calibration::calibrate::{calibrate, calibrate_with_map};
use crate::calibration::calibrate_map::MapInput;
use crate::dataset::data_set::{DataSet, LoadOptions, MemoryPoints};
use crate::psd_map::from_scan::{psd_map_of, PsdMapOutcome, PsdMapRequest};
use crate::simulation::simulate::{simulate_data, SimulateRequest, DEFAULT_RECORD_CYCLES};
use crate::simulation::simulate_scan::{scan_samples, ScanRequest};
use psdcal_psdmap::ModelChoice as PsdMapModel;

/// One seed's angle errors (rad) and the map's error against the truth.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SeedErrors {
    /// Calibrated with the map.
    pub map: f64,
    /// Calibrated with the map refined, its scan as the prior.
    pub refined: f64,
    /// Calibrated with `l1` freed.
    pub l1: f64,
    /// The same data without non-linearity.
    pub clean: f64,
    /// RMS of the map's error against the true field over the scan's
    /// interior, mm.
    pub map_error_mm: f64,
    /// The same for the refined map, mm.
    pub refined_map_error_mm: f64,
    /// The scan's noise per axis (√(σx² + σy²)/√2), mm.
    pub scan_noise_mm: f64,
}

/// The simulated scan of `request` as its file would hold it, in memory:
/// the measured points, or with `amplitudes` the electrode amplitudes only.
pub(crate) fn scan_in_memory(request: &ScanRequest, amplitudes: bool) -> Result<Scan> {
    let scanned = scan_samples(request)?;
    let rows = scanned
        .samples
        .iter()
        .enumerate()
        .map(|(i, s)| ScanRow {
            stage: s.stage,
            reading: if amplitudes {
                ScanReading::Amplitudes(s.amplitudes)
            } else {
                ScanReading::Point(s.measured)
            },
            // Rows after the header line.
            line_no: i + 2,
        })
        .collect();
    Ok(Scan {
        source: request.out.display().to_string(),
        rows,
    })
}

/// The map of `scan` with the model chosen by cross-validation (folds from
/// `seed`), and the same as a calibration's input named
/// `psd_map{seed}.json`.
pub(crate) fn fit_map(scan: &Scan, seed: u64) -> Result<(PsdMapOutcome, MapInput)> {
    let geometry = PsdGeometry::default();
    let fitted = psd_map_of(
        scan,
        &InputHashes::default(),
        &PsdMapRequest {
            scan: PathBuf::from(&scan.source),
            model: PsdMapModel::Auto,
            geometry,
            seed,
            command: String::new(),
            report: None,
            limits: Default::default(),
            force: false,
        },
    )?;
    let map = MapInput::in_memory(fitted.file.clone(), &map_name(seed), &geometry)?;
    Ok((fitted, map))
}

/// The name of seed `seed`'s map in messages.
fn map_name(seed: u64) -> String {
    format!("psd_map{seed}.json")
}

/// `set` calibrated with `map` held fixed or, with `refine`, refined.
pub(crate) fn calibrate_with(set: &DataSet, map: &MapInput, refine: bool) -> Result<Calibration> {
    let options = CalibrationOptions {
        psd_map: Some(PathBuf::from(&map.source)),
        refine_psd_map: refine,
        ..CalibrationOptions::default()
    };
    let calibrated = calibrate_with_map(set, &options, Some(map.clone()), &InputHashes::default())?;
    Ok(calibrated.record)
}

/// The data set of seed `seed` (lens 2, 40 dB, 12 images, with or without
/// the PSD's non-linearity), simulated in memory.
pub(crate) fn data_set(seed: u64, nonlinearity: bool) -> Result<DataSet> {
    let data = simulate_data(&SimulateRequest {
        lens: Lens::Two,
        snr_db: Some(40.0),
        imbalance: false,
        psd_distortion: false,
        psd_nonlinearity: nonlinearity,
        images: 12,
        template: TemplateKind::Scatter14,
        record_cycles: DEFAULT_RECORD_CYCLES,
        seed,
        out: PathBuf::new(),
        force: false,
    })?;
    let template = Template {
        source: "template.csv".into(),
        leds: data
            .template
            .iter()
            .enumerate()
            .map(|(i, led)| Led {
                id: led.id.clone(),
                x_mm: led.x_mm,
                y_mm: led.y_mm,
                z_mm: None,
                lines: led.lines.clone(),
                line_no: i + 2,
            })
            .collect(),
    };
    let observations = Observations {
        source: "observations.csv".into(),
        rows: data
            .observations
            .iter()
            .enumerate()
            .map(|(i, o)| Observation {
                image: o.image.clone(),
                led: o.led.clone(),
                x_mm: o.x_mm,
                y_mm: o.y_mm,
                line_no: i + 2,
            })
            .collect(),
    };
    DataSet::from_memory(
        template,
        MemoryPoints::Observations(observations),
        &LoadOptions::default(),
    )
}

/// The RMS angle error of a calibration (module documentation), rad.
pub(crate) fn aoa_error(record: &Calibration, nonlinearity: bool) -> Result<f64> {
    let truth = Model::standard(&SensorModel::paper_lens2());
    let geometry = PsdGeometry::default();
    let nl = PsdNonlinearity::new(geometry);
    let sensor = sensor_of(record)?;
    let (mut sum, mut n) = (0.0, 0);
    for i in 0..9 {
        for j in 0..9 {
            let ideal = Vector2::new(
                0.4 * geometry.lx * (i as f64 / 4.0 - 1.0),
                0.4 * geometry.ly * (j as f64 / 4.0 - 1.0),
            );
            let spot = truth.measured_from_ideal_to_tolerance(&ideal)?;
            let m = if nonlinearity {
                nl.reported(&spot)
            } else {
                spot
            };
            let est = sensor.aoa(&Measurement::Point(m), &LocateOptions::default())?;
            let e = est.aoa.direction.into_inner();
            let t = truth.direction_of_ideal(&ideal).into_inner();
            let angle = e.cross(&t).norm().atan2(e.dot(&t));
            sum += angle * angle;
            n += 1;
        }
    }
    Ok((sum / n as f64).sqrt())
}

/// The experiment for one seed (module documentation), in memory;
/// `amplitudes`: fit the map from the scan's amplitude form.
pub fn psd_map_seed(seed: u64, amplitudes: bool) -> Result<SeedErrors> {
    let scan = scan_in_memory(
        &ScanRequest {
            step_mm: 0.25,
            stage_sigma_um: 0.3,
            snr_db: Some(50.0),
            nonlinearity: true,
            geometry: PsdGeometry::default(),
            seed: 1000 + seed,
            out: PathBuf::from(format!("scan{seed}.csv")),
        },
        amplitudes,
    )?;
    let (fitted, map) = fit_map(&scan, seed)?;
    assert_eq!(fitted.file.fit.from_amplitudes, amplitudes);
    // The map against the true field (measured → spot) inside the scan.
    let map_error_mm = map_error(&fitted.fit.map, &fitted.fit.block)?;

    let noisy = data_set(seed, true)?;
    let map_record = calibrate_with(&noisy, &map, false)?;
    let map_rms = aoa_error(&map_record, true)?;
    let refined_record = calibrate_with(&noisy, &map, true)?;
    let refined = aoa_error(&refined_record, true)?;
    let refined_block: Vec<f64> = refined_record
        .psd_map
        .as_ref()
        .ok_or_else(|| Error::Input("the refined calibration lost its map".into()))?
        .parameters
        .iter()
        .map(|(_, v)| *v)
        .collect();
    let refined_map_error_mm = map_error(&fitted.fit.map, &refined_block)?;
    // The default fit with l1 freed too.
    let mut free_l1 = CalibrationOptions::default();
    free_l1.free.push(Param::L1);
    let l1 = aoa_error(&calibrate(&noisy, &free_l1)?.record, true)?;
    let clean_set = data_set(seed, false)?;
    let clean = aoa_error(
        &calibrate(&clean_set, &CalibrationOptions::default())?.record,
        false,
    )?;
    Ok(SeedErrors {
        map: map_rms,
        refined,
        refined_map_error_mm,
        l1,
        clean,
        map_error_mm,
        scan_noise_mm: fitted.fit.sigma_mm.norm() / 2f64.sqrt(),
    })
}

/// The RMS of a map's error `d(m) − (spot(m) − m)` against the true
/// non-linearity over a 41 × 41 grid of ±4.3 mm (inside the scan), mm.
pub(crate) fn map_error(map: &psdcal_model::stages::PsdMap, block: &[f64]) -> Result<f64> {
    let nl = PsdNonlinearity::new(PsdGeometry::default());
    let mut s = 0.0;
    for i in 0..41 {
        for j in 0..41 {
            let m = Vector2::new(-4.3 + 8.6 * i as f64 / 40.0, -4.3 + 8.6 * j as f64 / 40.0);
            let truth = nl.spot(&m).ok_or_else(|| {
                Error::Input("the true field is undefined inside the scan".into())
            })? - m;
            s += (map.displacement(block, &m) - truth).norm_squared();
        }
    }
    Ok((s / 1681.0).sqrt())
}

/// RMS over seeds of one field.
pub fn pooled(errors: &[SeedErrors], field: fn(&SeedErrors) -> f64) -> f64 {
    (errors.iter().map(|e| field(e).powi(2)).sum::<f64>() / errors.len() as f64).sqrt()
}

#[cfg(test)]
mod tests {
    #[test]
    fn pooling_is_the_rms_over_seeds() {
        let e = |map: f64| super::SeedErrors {
            map,
            refined: 0.0,
            refined_map_error_mm: 0.0,
            l1: 0.0,
            clean: 0.0,
            map_error_mm: 0.0,
            scan_noise_mm: 0.0,
        };
        let p = super::pooled(&[e(3.0), e(4.0)], |x| x.map);
        assert!((p - 12.5f64.sqrt()).abs() < 1e-15);
    }
}
