//! psd_map.json: the PSD's non-linearity map fitted to a lensless scan by
//! `psdcal psd-map` (docs/formats.md, docs/model.md §8.3), read by
//! `psdcal calibrate --psd-map`.
//!
//! A JSON object: `format` = `"psdcal-psd-map"`, `version` = 1; `sensor`
//! (`lx_mm`, `ly_mm`: the map belongs to a sensor of this size); `model`
//! (`poly:N`, `spline:N`); `stage` (the stage's structure: `basis`, `order`
//! or `cells`, `frame_mm` = `[x0, y0, x1, y1]`, `hull_mm` = the scan's hull,
//! counter-clockwise); `coefficients` (`x`, `y`: the `K` coefficients of
//! each axis, mm, in the basis's order); `covariance` (`sigma_x_mm`,
//! `sigma_y_mm`, and `unit`: the K×K matrix `U`, so that the x coefficients'
//! covariance is `σ_x² U`, the y coefficients' `σ_y² U`, without cross
//! terms); `fit` (points, rejected lines, folds, the cross-validated and
//! residual RMS, the noise and the map's own error in µm, the candidates
//! with their cross-validated RMS); `residuals` (per scan point: `x_mm`,
//! `y_mm` measured, `dx_um`, `dy_um` stage minus corrected point, and
//! `rejected`: the indices of the points rejected as outliers);
//! `provenance` (as in calibration.json).

use std::path::Path;

use nalgebra::DMatrix;
use psdcal_model::stages::PsdMap;
use psdcal_model::{ParameterCovariance, PsdGeometry, Stage};
use serde::{Deserialize, Serialize};

use crate::atomic::write_atomic_bytes;
use crate::calibration::{Provenance, SensorSize};
use crate::limits::ReadLimits;
use crate::{IoError, Location};

/// The format name of psd_map.json.
pub const PSD_MAP_FORMAT: &str = "psdcal-psd-map";
/// The version this psdcal writes.
pub const PSD_MAP_VERSION: u32 = 1;
/// Two sensor sides that differ by less than this (mm) are the same size.
pub const SENSOR_SIZE_TOLERANCE_MM: f64 = 1e-6;

/// The coefficients of each axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapCoefficients {
    /// x coefficients, mm.
    pub x: Vec<f64>,
    /// y coefficients, mm.
    pub y: Vec<f64>,
}

/// The coefficients' covariance: `σ_x² U` and `σ_y² U`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapCovarianceRecord {
    /// Scan noise along x, mm.
    pub sigma_x_mm: f64,
    /// Scan noise along y, mm.
    pub sigma_y_mm: f64,
    /// `U`, K×K rows.
    pub unit: Vec<Vec<f64>>,
}

/// A candidate of the model choice.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapCandidateRecord {
    /// `poly:N` or `spline:N`.
    pub model: String,
    /// Its cross-validated RMS, µm.
    pub cv_rms_um: f64,
}

/// The fit's summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapFitRecord {
    /// Scan points read.
    pub points: usize,
    /// Whether they came from electrode amplitudes.
    pub from_amplitudes: bool,
    /// File lines of the points rejected as outliers.
    pub rejected_lines: Vec<usize>,
    /// Folds of the cross-validation.
    pub folds: usize,
    /// Cross-validated RMS error of the chosen model, µm.
    pub cv_rms_um: f64,
    /// RMS residual of the fit, µm.
    pub rms_um: f64,
    /// Scan noise per axis, µm.
    pub sigma_x_um: f64,
    /// Scan noise per axis, µm.
    pub sigma_y_um: f64,
    /// RMS standard error of the map at the scan points, µm.
    pub map_sigma_um: f64,
    /// Effective coefficients per axis.
    pub effective_terms: f64,
    /// Every candidate tried.
    pub candidates: Vec<MapCandidateRecord>,
}

/// Residuals per scan point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapResidualsRecord {
    /// Indices (from 0, into these arrays) of the points the fit rejected
    /// as outliers (absent in files of older psdcal: none known).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub rejected: Vec<usize>,
    /// Measured x, mm.
    pub x_mm: Vec<f64>,
    /// Measured y, mm.
    pub y_mm: Vec<f64>,
    /// Residual along x, µm.
    pub dx_um: Vec<f64>,
    /// Residual along y, µm.
    pub dy_um: Vec<f64>,
}

impl MapResidualsRecord {
    /// The arrays are of one length, their numbers finite, the rejected
    /// indices among the points.
    pub fn check(&self) -> Result<(), String> {
        let n = self.x_mm.len();
        if [&self.y_mm, &self.dx_um, &self.dy_um]
            .iter()
            .any(|v| v.len() != n)
        {
            return Err(
                "residuals.x_mm, y_mm, dx_um and dy_um must hold one value per scan point each"
                    .into(),
            );
        }
        let values = [&self.x_mm, &self.y_mm, &self.dx_um, &self.dy_um];
        if values.iter().any(|v| v.iter().any(|x| !x.is_finite())) {
            return Err("the residuals must be finite".into());
        }
        if let Some(i) = self.rejected.iter().find(|&&i| i >= n) {
            return Err(format!(
                "residuals.rejected: index {i} is beyond the {n} scan points"
            ));
        }
        Ok(())
    }
}

/// psd_map.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PsdMapFile {
    /// `"psdcal-psd-map"`.
    pub format: String,
    /// 1.
    pub version: u32,
    /// The sensor the map belongs to.
    pub sensor: SensorSize,
    /// `poly:N` or `spline:N`.
    pub model: String,
    /// The stage's structure ([`Stage::configuration`]).
    pub stage: serde_json::Value,
    /// The coefficients.
    pub coefficients: MapCoefficients,
    /// Their covariance.
    pub covariance: MapCovarianceRecord,
    /// The fit.
    pub fit: MapFitRecord,
    /// Residuals per scan point.
    pub residuals: MapResidualsRecord,
    /// Where it came from.
    pub provenance: Provenance,
}

/// A map file as a model stage.
#[derive(Debug, Clone)]
pub struct LoadedPsdMap {
    /// The stage.
    pub stage: PsdMap,
    /// Its block `(a_x, a_y)`, mm.
    pub block: Vec<f64>,
    /// The block's covariance by the stage's names.
    pub covariance: ParameterCovariance,
}

impl PsdMapFile {
    /// The stage, its block and covariance; `source` names the file in
    /// errors. Checks the structure, the lengths and that every number is
    /// finite.
    pub fn to_stage(&self, source: &str) -> Result<LoadedPsdMap, IoError> {
        let bad = |message: String| IoError::Invalid {
            at: Location::file(source),
            message,
        };
        let stage = PsdMap::from_configuration(&self.stage).map_err(|e| bad(e.to_string()))?;
        let k = stage.terms();
        let c = &self.coefficients;
        if c.x.len() != k || c.y.len() != k {
            return Err(bad(format!(
                "coefficients.x and .y hold {} and {} values; expected {k} each for {}",
                c.x.len(),
                c.y.len(),
                stage.basis().label()
            )));
        }
        let cov = &self.covariance;
        let finite = c.x.iter().chain(&c.y).all(|v| v.is_finite())
            && cov.sigma_x_mm.is_finite()
            && cov.sigma_y_mm.is_finite()
            && cov.sigma_x_mm >= 0.0
            && cov.sigma_y_mm >= 0.0;
        if !finite {
            return Err(bad(
                "the coefficients and the sigmas must be finite (sigmas not negative)".into(),
            ));
        }
        if cov.unit.len() != k || cov.unit.iter().any(|r| r.len() != k) {
            return Err(bad(format!("covariance.unit must be {k} × {k}")));
        }
        self.residuals.check().map_err(bad)?;
        let unit = DMatrix::from_fn(k, k, |i, j| cov.unit[i][j]);
        let mut m = DMatrix::zeros(2 * k, 2 * k);
        m.view_mut((0, 0), (k, k))
            .copy_from(&(&unit * cov.sigma_x_mm.powi(2)));
        m.view_mut((k, k), (k, k))
            .copy_from(&(&unit * cov.sigma_y_mm.powi(2)));
        let names = stage.parameters().iter().map(|p| p.name.clone()).collect();
        let covariance =
            ParameterCovariance::new(names, m).map_err(|e| bad(format!("covariance.unit: {e}")))?;
        let block = c.x.iter().chain(&c.y).copied().collect();
        Ok(LoadedPsdMap {
            stage,
            block,
            covariance,
        })
    }

    /// Refuses a map of a sensor of another size than `geometry`.
    pub fn check_sensor(&self, source: &str, geometry: &PsdGeometry) -> Result<(), IoError> {
        let s = &self.sensor;
        if (s.lx_mm - geometry.lx).abs() > SENSOR_SIZE_TOLERANCE_MM
            || (s.ly_mm - geometry.ly).abs() > SENSOR_SIZE_TOLERANCE_MM
        {
            return Err(IoError::Invalid {
                at: Location::file(source),
                message: format!(
                    "the map is of a {} mm × {} mm sensor, this one is {} mm × {} mm; expected \
                     a map scanned on this sensor (or give --lx/--ly)",
                    s.lx_mm, s.ly_mm, geometry.lx, geometry.ly
                ),
            });
        }
        Ok(())
    }
}

/// Writes psd_map.json atomically.
pub fn write_psd_map(path: impl AsRef<Path>, file: &PsdMapFile) -> Result<(), IoError> {
    let path = path.as_ref();
    let source = path.display().to_string();
    file.to_stage(&source)?;
    let mut text = serde_json::to_string_pretty(file).map_err(|e| IoError::Invalid {
        at: Location::file(&source),
        message: format!("cannot encode the map as JSON: {e}"),
    })?;
    text.push('\n');
    write_atomic_bytes(path, text.as_bytes())
}

/// Reads psd_map.json (bounded) and checks it.
pub fn read_psd_map(path: impl AsRef<Path>) -> Result<(PsdMapFile, LoadedPsdMap), IoError> {
    read_psd_map_with(path, ReadLimits::default())
}

/// [`read_psd_map`] within `limits` (docs/formats.md, "Limits").
pub fn read_psd_map_with(
    path: impl AsRef<Path>,
    limits: ReadLimits,
) -> Result<(PsdMapFile, LoadedPsdMap), IoError> {
    let path = path.as_ref();
    let text = crate::limits::read_text(path, limits)?;
    psd_map_from_text(&path.display().to_string(), &text)
}

/// [`read_psd_map`] from a reader (bounded); `source` names it in messages.
pub fn psd_map_from_reader(
    source: &str,
    reader: impl std::io::Read,
) -> Result<(PsdMapFile, LoadedPsdMap), IoError> {
    psd_map_from_reader_with(source, reader, ReadLimits::default())
}

/// [`psd_map_from_reader`] within `limits` (docs/formats.md, "Limits").
pub fn psd_map_from_reader_with(
    source: &str,
    reader: impl std::io::Read,
    limits: ReadLimits,
) -> Result<(PsdMapFile, LoadedPsdMap), IoError> {
    psd_map_from_text(
        source,
        &crate::limits::read_text_from(source, reader, limits)?,
    )
}

/// Parses and checks psd_map.json's text; `source` names it in messages.
fn psd_map_from_text(source: &str, text: &str) -> Result<(PsdMapFile, LoadedPsdMap), IoError> {
    let source = source.to_string();
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| crate::error::json_error(&source, &e))?;
    let bad = |message: String| IoError::Invalid {
        at: Location::file(&source),
        message,
    };
    match value.get("format").and_then(|v| v.as_str()) {
        Some(PSD_MAP_FORMAT) => {}
        other => {
            return Err(bad(format!(
                "expected format \"{PSD_MAP_FORMAT}\", found {}",
                other.map_or("none".to_string(), |f| format!(
                    "\"{}\"",
                    crate::limits::excerpt(f).escape_debug()
                ))
            )))
        }
    }
    if let Some(v) = value.get("version").and_then(|v| v.as_u64()) {
        if v > u64::from(PSD_MAP_VERSION) {
            return Err(bad(format!(
                "map file version {v} was written by a newer psdcal; upgrade psdcal"
            )));
        }
    }
    let file: PsdMapFile =
        serde_json::from_str(text).map_err(|e| crate::error::json_error(&source, &e))?;
    let loaded = file.to_stage(&source)?;
    Ok((file, loaded))
}
