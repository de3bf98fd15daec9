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
use psdcal_calib::{CalibrateOptions, CalibrationData, CalibrationResult};
use psdcal_io::{
    psd_map_from_reader_with, Calibration, LoadedPsdMap, PsdMapFile, PsdMapStageCovariance,
    PsdMapStageRecord,
};
use psdcal_locate::{CalibratedSensor, SensorPsdMap};
use psdcal_model::{Model, ParameterCovariance, PsdGeometry, Stage};

use crate::base::error::{Error, Result};
use crate::base::provenance::InputHashes;

/// A map file read for a calibration.
#[derive(Debug, Clone)]
pub(crate) struct MapInput {
    pub file: PsdMapFile,
    pub loaded: LoadedPsdMap,
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
    file.check_sensor(&path.display().to_string(), geometry)?;
    Ok(MapInput { file, loaded })
}

/// Refuses data points outside the map's hull (`points`: image, LED,
/// measured point).
pub(crate) fn check_data_in_hull(
    map: &MapInput,
    path: &Path,
    points: &[(&str, String, nalgebra::Vector2<f64>)],
) -> Result<()> {
    let outside: Vec<_> = points
        .iter()
        .filter(|(_, _, m)| !map.loaded.stage.contains_input(m))
        .collect();
    match outside.first() {
        None => Ok(()),
        Some((image, led, m)) => Err(Error::DataOutsidePsdMap {
            map: path.display().to_string(),
            outside: outside.len(),
            points: points.len(),
            first: format!("image {image}, LED {led} at ({:.4}, {:.4}) mm", m.x, m.y),
        }),
    }
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

/// The refined map's stage of calibration.json: its coefficients from
/// `result`'s model, `matrix` their block of the joint covariance and
/// `cross` their covariance with the other estimated parameters, to which
/// `result`'s covariance is narrowed (the record's `covariance` names the
/// model's scalar parameters only).
pub(crate) fn refined_stage(
    result: &mut CalibrationResult,
    map: &MapInput,
) -> Result<PsdMapStageRecord> {
    let stage = &map.loaded.stage;
    let names: Vec<String> = stage.parameters().iter().map(|p| p.name.clone()).collect();
    let joint = &result.covariance.parameters;
    let others: Vec<String> = joint
        .names()
        .iter()
        .filter(|n| !names.contains(n))
        .cloned()
        .collect();
    let index = |n: &String| {
        joint
            .index(n)
            .ok_or_else(|| Error::Input(format!("the refined map's '{n}' has no covariance")))
    };
    let (rows, cols) = (
        names.iter().map(index).collect::<Result<Vec<_>>>()?,
        others.iter().map(index).collect::<Result<Vec<_>>>()?,
    );
    let m = joint.matrix();
    let table = |a: &[usize], b: &[usize]| -> Vec<Vec<f64>> {
        a.iter()
            .map(|i| b.iter().map(|j| m[(*i, *j)]).collect())
            .collect()
    };
    let (matrix, cross) = (table(&rows, &rows), table(&rows, &cols));
    let parameters = names
        .iter()
        .map(|n| {
            result
                .model
                .get(n)
                .map(|v| (n.clone(), v))
                .ok_or_else(|| Error::Input(format!("the refined model has no '{n}'")))
        })
        .collect::<Result<Vec<_>>>()?;
    let narrowed = ParameterCovariance::new(
        others.clone(),
        DMatrix::from_fn(cols.len(), cols.len(), |i, j| m[(cols[i], cols[j])]),
    )
    .map_err(|e| Error::Input(format!("the calibration's covariance: {e}")))?;
    result.covariance.parameters = narrowed;
    let c = &map.file.covariance;
    Ok(PsdMapStageRecord {
        configuration: stage.configuration(),
        parameters,
        covariance: PsdMapStageCovariance {
            sigma_x_mm: c.sigma_x_mm,
            sigma_y_mm: c.sigma_y_mm,
            unit: c.unit.clone(),
            cross,
            matrix: Some(matrix),
        },
        estimated: true,
        scan: Some(crate::psd_map::from_scan::scan_summary(&map.file, stage)),
    })
}

/// Carries the map's covariance into `result`'s and returns the
/// calibration.json stage of the map (with the cross-covariance).
pub(crate) fn carry(
    result: &mut CalibrationResult,
    data: &CalibrationData,
    options: &CalibrateOptions,
    map: &MapInput,
) -> Result<PsdMapStageRecord> {
    let carried = psdcal_calib::carry_fixed_covariance(
        data,
        &result.model,
        &result.poses,
        &options.refine,
        &result.covariance.parameters,
        &map.loaded.covariance,
    )
    .map_err(Error::Calibrate)?;
    result.covariance.parameters = carried.parameters;
    let stage = &map.loaded.stage;
    let c = &map.file.covariance;
    Ok(PsdMapStageRecord {
        configuration: stage.configuration(),
        parameters: stage
            .parameters()
            .iter()
            .map(|p| p.name.clone())
            .zip(map.loaded.block.iter().copied())
            .collect(),
        covariance: PsdMapStageCovariance {
            sigma_x_mm: c.sigma_x_mm,
            sigma_y_mm: c.sigma_y_mm,
            unit: c.unit.clone(),
            cross: (0..carried.cross.nrows())
                .map(|i| carried.cross.row(i).iter().copied().collect())
                .collect(),
            matrix: None,
        },
        estimated: false,
        scan: Some(crate::psd_map::from_scan::scan_summary(&map.file, stage)),
    })
}

/// The sensor of a calibration with a map: the map first, the joint
/// covariance of the estimated parameters and the map's coefficients
/// `[[C_θ, C_mθᵀ], [C_mθ, C_m]]`; `estimated` is the record's covariance.
pub(crate) fn sensor_with_map(
    calibration: &Calibration,
    map: &PsdMapStageRecord,
    sensor: CalibratedSensor,
    estimated: ParameterCovariance,
) -> std::result::Result<CalibratedSensor, String> {
    let nt = estimated.len();
    let (stage, block) = map.to_stage(nt)?;
    let cm = map.map_covariance(&stage)?;
    let nm = cm.len();
    let mut joint = DMatrix::zeros(nt + nm, nt + nm);
    joint
        .view_mut((0, 0), (nt, nt))
        .copy_from(estimated.matrix());
    joint.view_mut((nt, nt), (nm, nm)).copy_from(cm.matrix());
    for i in 0..nm {
        for j in 0..nt {
            let v = map.covariance.cross[i][j];
            joint[(nt + i, j)] = v;
            joint[(j, nt + i)] = v;
        }
    }
    let names = estimated
        .names()
        .iter()
        .chain(cm.names())
        .cloned()
        .collect();
    let joint = ParameterCovariance::new(names, joint).map_err(|e| e.to_string())?;
    let mut sensor = sensor
        .with_covariance(joint)
        .with_psd_map(SensorPsdMap { stage, block });
    if calibration.valid_region.is_some() {
        sensor = sensor.with_valid_region(calibration.valid_region());
    }
    Ok(sensor)
}
