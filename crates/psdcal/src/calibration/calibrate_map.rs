//! `calibrate --psd-map`: the PSD's non-linearity map (psd_map.json,
//! docs/model.md §8.3) as the first stage of the calibrated model, held
//! fixed with its covariance carried into the parameters' (psdcal-calib's
//! `carry_fixed_covariance`), or with `--refine-psd-map` refined with the
//! scan's covariance as the prior (psdcal-calib's `CalibrateOptions::prior`:
//! the joint covariance then holds the map's uncertainty, nothing is
//! carried); through calibration.json's `psd_map` stage it reaches every
//! angle's uncertainty.

use std::path::Path;

use nalgebra::DMatrix;
use psdcal_calib::BlockCovariance;
use psdcal_io::{
    psd_map_from_reader_with, LoadedPsdMap, PsdMapFile, PsdMapStageCovariance, PsdMapStageRecord,
};
use psdcal_locate::{CalibratedSensor, SensorPsdMap};
use psdcal_model::{Model, ParameterCovariance, PsdGeometry, Stage};

use crate::base::error::Result;
use crate::base::provenance::InputHashes;

/// A map file read for a calibration.
#[derive(Debug, Clone)]
pub(crate) struct MapInput {
    /// The file's name, for messages.
    pub source: String,
    pub file: PsdMapFile,
    pub loaded: LoadedPsdMap,
}

impl MapInput {
    /// A map in memory, named `source` in messages, checked against the
    /// sensor as a file would be.
    pub(crate) fn in_memory(
        file: PsdMapFile,
        source: &str,
        geometry: &PsdGeometry,
    ) -> Result<Self> {
        let loaded = file.to_stage(source)?;
        file.check_sensor(source, geometry)?;
        Ok(MapInput {
            source: source.to_string(),
            file,
            loaded,
        })
    }
}

/// Reads psd_map.json once (within `limits`), adding it with the hash of
/// the bytes read to `inputs`, and checks it belongs to a sensor of
/// `geometry`.
pub(crate) fn load(
    path: &Path,
    geometry: &PsdGeometry,
    limits: psdcal_io::ReadLimits,
    inputs: &mut InputHashes,
) -> Result<MapInput> {
    let (file, loaded) = inputs.read(path, |s, r| psd_map_from_reader_with(s, r, limits))?;
    let source = path.display().to_string();
    file.check_sensor(&source, geometry)?;
    Ok(MapInput {
        source,
        file,
        loaded,
    })
}

/// `base` with the map first among its distortion stages, at its values.
pub(crate) fn with_map(base: &Model, map: &MapInput) -> Result<Model> {
    let stage = &map.loaded.stage;
    let mut model = base.with_stage(0, Box::new(stage.clone()))?;
    for (p, v) in stage.parameters().iter().zip(&map.loaded.block) {
        model.set(&p.name, *v)?;
    }
    Ok(model)
}

/// The map's stage of calibration.json from the calibration's settled
/// block: held fixed (its covariance carried: `cross` only) or refined
/// (`matrix` its block of the joint covariance, `cross` with the other
/// estimated parameters).
pub(crate) fn stage_record(map: &MapInput, block: &BlockCovariance) -> PsdMapStageRecord {
    let stage = &map.loaded.stage;
    let c = &map.file.covariance;
    let rows = |m: &DMatrix<f64>| -> Vec<Vec<f64>> {
        (0..m.nrows())
            .map(|i| m.row(i).iter().copied().collect())
            .collect()
    };
    PsdMapStageRecord {
        configuration: stage.configuration(),
        parameters: block.parameters.clone(),
        covariance: PsdMapStageCovariance {
            sigma_x_mm: c.sigma_x_mm,
            sigma_y_mm: c.sigma_y_mm,
            unit: c.unit.clone(),
            cross: rows(&block.cross),
            matrix: block.matrix.as_ref().map(rows),
        },
        estimated: block.matrix.is_some(),
        scan: Some(crate::psd_map::from_scan::scan_summary(&map.file, stage)),
    }
}

/// The sensor of a calibration with a map: the map first, the joint
/// covariance of the estimated parameters and the map's coefficients
/// `[[C_θ, C_mθᵀ], [C_mθ, C_m]]`; `estimated` is the record's covariance.
pub(crate) fn sensor_with_map(
    map: &PsdMapStageRecord,
    sensor: CalibratedSensor,
    estimated: ParameterCovariance,
) -> std::result::Result<CalibratedSensor, String> {
    let nt = estimated.len();
    let (stage, block) = map.to_stage(nt)?;
    let cm = map.map_covariance(&stage)?;
    let cross = DMatrix::from_fn(cm.len(), nt, |i, j| map.covariance.cross[i][j]);
    let joint = estimated.joint(&cm, &cross).map_err(|e| e.to_string())?;
    // `with_psd_map` recomputes the valid region for the whole chain (a
    // stored one is never trusted).
    Ok(sensor
        .with_covariance(joint)
        .with_psd_map(SensorPsdMap { stage, block }))
}
