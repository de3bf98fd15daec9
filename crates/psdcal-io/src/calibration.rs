//! calibration.json: the result of a calibration (docs/formats.md). Version 2
//! (module `v2`: stages, flat parameters, diagnostics, provenance) is
//! written by default; version 1, below, is still read, and written for a
//! record whose `version` is 1. Both read into the same [`Calibration`].
//!
//! Version 1:
//!
//! ```text
//! { "format": "psdcal-calibration", "version": 1,
//!   "software": {"name": "psdcal", "version": "0.1.0"},
//!   "sensor": {"lx_mm": 9.0, "ly_mm": 9.0},
//!   "intrinsics": {"f_mm": 8.0, "cx_mm": 0.5, "cy_mm": -0.7, "skew": 0.0},
//!   "distortion": {"k1": 0.01, "k2": 3e-5, "k3": 0.0, "p1": 0.0, "p2": 0.0, "l1": 0.0, "l2": 0.0},
//!   "estimated": ["f", "cx", "cy", "k1", "k2"],
//!   "fixed": ["skew", "k3", "p1", "p2", "l1", "l2"],
//!   "gains": null | {"x1": 1.0, "x2": 1.01, "y1": 0.99, "y2": 1.0, "estimated": true},
//!   "std": {"f": 0.01, "cx": 0.002, ...},
//!   "covariance": {"parameters": ["f", "cx", ...], "matrix": [[...], ...]},
//!   "fit": {"cost": "template", "residual_mm2": 1.2, "rms_template_mm": 0.1,
//!           "rms_image_mm": 0.001, "iterations": 12, "points": 126, "images": 9,
//!           "termination": "relative cost change below 1e-12"},
//!   "images": [{"id": "1", "rvec": [0.1, 0.0, 0.0], "t_mm": [0.0, 0.0, 600.0],
//!               "rms_mm": 0.1, "points": 14}] }
//! ```
//!
//! Units: millimetres; distortion coefficients as in docs/model.md §2 (`k1` in
//! mm⁻², …); `rvec` is a Rodrigues vector in radians (sensor-from-template
//! pose); gains are relative channel gains (docs/model.md §1). `std` has one entry
//! per estimated parameter, named as in `estimated`, plus `g_x2`, `g_y1`,
//! `g_y2` when the gains were estimated; `covariance.parameters` lists the
//! same names (its order, not the key order of `std`, which JSON does not
//! keep, is the order) and `matrix` is square and symmetric.
//!
//! Compatibility: a file of this or an older version is read; a newer
//! version is refused with a message saying so; unknown fields are ignored,
//! so later versions may add fields. Reading reports JSON errors and invalid
//! values with file, line and column; cross-field checks name the fields.
//! Writing validates first, so no NaN or infinity is ever written, and is
//! atomic ([`crate::write_atomic`]).

use std::path::Path;

use psdcal_model::{
    ChannelGains, Distortion, Intrinsics, Param, PsdGeometry, SensorModel, ValidRegion,
};
use serde::{Deserialize, Serialize};

use crate::atomic::write_atomic_bytes;
use crate::error::{json_error, IoError};
use crate::limits::ReadLimits;
use crate::location::Location;

mod provenance;
mod psd_map_stage;
mod records;
mod region;
mod rules;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_v2;
mod v2;

pub use provenance::{Diagnostic, InputFile, Provenance};
pub use psd_map_stage::{
    PsdMapScanRecord, PsdMapStageCovariance, PsdMapStageRecord, ScanResidualCells,
};
pub use records::{
    BootstrapRecord, CostKind, Covariance, FitSummary, GainsRecord, ImageFit, IntrinsicsRecord,
    SensorSize, Software, StdDevs,
};
pub use region::ValidRegionRecord;
use rules::{de_format, de_version};

/// The `format` name of calibration.json.
pub const CALIBRATION_FORMAT: &str = "psdcal-calibration";
/// The newest calibration.json version this crate reads, and the one a new
/// record ([`Calibration::from_model`]) is written in.
pub const CALIBRATION_VERSION: u32 = 2;
/// Names of the estimated relative gains in `std` and `covariance` (the
/// gains stage's parameter names, defined in psdcal-model).
pub use psdcal_model::stages::gains::GAIN_NAMES;

/// A calibration result, as stored in calibration.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Always [`CALIBRATION_FORMAT`].
    #[serde(deserialize_with = "de_format")]
    pub format: String,
    /// Format version, at most [`CALIBRATION_VERSION`].
    #[serde(deserialize_with = "de_version")]
    pub version: u32,
    /// The program that wrote the file.
    pub software: Software,
    /// Active area of the PSD.
    pub sensor: SensorSize,
    /// Pinhole intrinsics.
    pub intrinsics: IntrinsicsRecord,
    /// Distortion coefficients by name (docs/model.md §2).
    pub distortion: Distortion,
    /// Model parameters the fit estimated.
    pub estimated: Vec<Param>,
    /// Model parameters held fixed.
    pub fixed: Vec<Param>,
    /// Channel gains, if an electrical calibration was used.
    pub gains: Option<GainsRecord>,
    /// Standard deviation of each estimated parameter.
    pub std: StdDevs,
    /// Covariance of the estimated parameters.
    pub covariance: Covariance,
    /// Summary of the fit.
    pub fit: FitSummary,
    /// Per-image poses and errors.
    pub images: Vec<ImageFit>,
    /// What the fit noticed (version 2; empty in version 1 files).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub diagnostics: Vec<Diagnostic>,
    /// Where the calibration came from (version 2; absent in version 1 files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub provenance: Option<Provenance>,
    /// Where the model is one-to-one (version 2, docs/model.md §8.2; written
    /// when present, [`Calibration::store_valid_region`]); `None`: not stored
    /// (version 1 files, older version 2 files), computed from the model when
    /// needed ([`Calibration::valid_region`]).
    #[serde(skip)]
    pub valid_region: Option<ValidRegionRecord>,
    /// The PSD's non-linearity map, first among the distortion stages
    /// (version 2 only, docs/model.md §8.3); `None` without one.
    #[serde(skip)]
    pub psd_map: Option<PsdMapStageRecord>,
    /// The y axis's own scale (version 2 only, docs/model.md §3.3): the
    /// `aspect` stage between `psd_radial` and `lens`; `None` without one.
    #[serde(skip)]
    pub aspect: Option<AspectRecord>,
}

/// The aspect stage of a calibration: `fy = f (1 + a)` (docs/model.md §3.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AspectRecord {
    /// The aspect `a` (dimensionless, above −1).
    pub a: f64,
    /// Whether the fit estimated it.
    pub estimated: bool,
}

impl Calibration {
    /// A calibration holding `model` with nothing estimated (every parameter
    /// fixed), no gains, an empty covariance, no fit and no images.
    pub fn from_model(model: &SensorModel, geometry: &PsdGeometry) -> Self {
        let i = &model.intrinsics;
        Self {
            format: CALIBRATION_FORMAT.to_string(),
            version: CALIBRATION_VERSION,
            software: Software::current(),
            sensor: SensorSize {
                lx_mm: geometry.lx,
                ly_mm: geometry.ly,
            },
            intrinsics: IntrinsicsRecord {
                f_mm: i.f,
                cx_mm: i.cx,
                cy_mm: i.cy,
                skew: i.skew,
            },
            distortion: model.distortion,
            estimated: Vec::new(),
            fixed: Param::ALL.to_vec(),
            gains: None,
            std: StdDevs::default(),
            covariance: Covariance::default(),
            fit: FitSummary::default(),
            images: Vec::new(),
            diagnostics: Vec::new(),
            provenance: None,
            valid_region: None,
            psd_map: None,
            aspect: None,
        }
    }

    /// Declares which parameters were estimated; the others, in
    /// [`Param::ALL`] order, become `fixed`.
    pub fn set_estimated(&mut self, estimated: &[Param]) {
        self.estimated = estimated.to_vec();
        self.fixed = Param::ALL
            .into_iter()
            .filter(|p| !estimated.contains(p))
            .collect();
    }

    /// The sensor model.
    pub fn to_model(&self) -> SensorModel {
        let i = &self.intrinsics;
        SensorModel {
            intrinsics: Intrinsics {
                f: i.f_mm,
                cx: i.cx_mm,
                cy: i.cy_mm,
                skew: i.skew,
            },
            distortion: self.distortion,
        }
    }

    /// The PSD's active area.
    pub fn geometry(&self) -> PsdGeometry {
        PsdGeometry {
            lx: self.sensor.lx_mm,
            ly: self.sensor.ly_mm,
        }
    }

    /// The model's valid region (docs/model.md §8.2): the stored one, or
    /// computed from the model when the file has none.
    pub fn valid_region(&self) -> ValidRegion {
        let geometry = self.geometry();
        self.valid_region
            .as_ref()
            .and_then(|r| r.to_region(&geometry).ok())
            .unwrap_or_else(|| ValidRegion::of_sensor_model(&self.to_model(), &geometry))
    }

    /// Computes the valid region of the model and stores it in the record.
    pub fn store_valid_region(&mut self) {
        let region = ValidRegion::of_sensor_model(&self.to_model(), &self.geometry());
        self.valid_region = Some(ValidRegionRecord::from_region(&region));
    }

    /// The relative channel gains, if any.
    pub fn gains(&self) -> Option<ChannelGains> {
        self.gains.as_ref().map(GainsRecord::to_gains)
    }

    /// Names `std` and `covariance` must hold: the estimated parameters,
    /// then the gains when estimated.
    pub fn estimated_names(&self) -> Vec<&'static str> {
        let mut names: Vec<&'static str> = self.estimated.iter().map(|p| p.name()).collect();
        if self.gains.is_some_and(|g| g.estimated) {
            names.extend(GAIN_NAMES);
        }
        if self.aspect.is_some_and(|a| a.estimated) {
            names.push("a");
        }
        names
    }

    /// Checks every rule of the format; `source` names the file in the error.
    pub fn validate(&self, source: &str) -> Result<(), IoError> {
        self.check().map_err(|message| IoError::Invalid {
            at: Location::file(source),
            message,
        })
    }

    /// Parses and validates calibration.json text; `source` names it in
    /// messages.
    pub fn from_json_str(source: &str, text: &str) -> Result<Self, IoError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // Format and version first, so that a file from a newer psdcal is
        // refused as such rather than for a field this version does not know.
        if let Err(e) = serde_json::from_str::<Header>(text) {
            return Err(match newer_version(text) {
                Some(found) => IoError::NewerVersion {
                    file: source.to_string(),
                    line: e.line().max(1),
                    column: e.column(),
                    found,
                    supported: CALIBRATION_VERSION,
                },
                None => json_error(source, &e),
            });
        }
        let version = serde_json::from_str::<Header>(text)
            .map(|h| h._version)
            .unwrap_or(CALIBRATION_VERSION);
        let mut calibration: Calibration = if version >= 2 {
            let file: v2::FileV2 =
                serde_json::from_str(text).map_err(|e| json_error(source, &e))?;
            file.into_record().map_err(|message| IoError::Invalid {
                at: Location::file(source),
                message,
            })?
        } else {
            serde_json::from_str(text).map_err(|e| json_error(source, &e))?
        };
        // A JSON object's keys have no order (RFC 8259): a file whose keys a
        // tool sorted (`jq -S`, Python's `sort_keys`) reads the same. `std`
        // follows `covariance.parameters`, which is an array.
        calibration.std.order_as(&calibration.covariance.parameters);
        calibration.validate(source)?;
        Ok(calibration)
    }

    /// Parses calibration.json bytes; `source` names it in messages.
    pub fn from_json_bytes(source: &str, bytes: &[u8]) -> Result<Self, IoError> {
        let text = std::str::from_utf8(bytes).map_err(|e| {
            let offset = e.valid_up_to();
            let line = 1 + bytes
                .get(..offset)
                .map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count());
            IoError::Encoding {
                at: Location::line(source, line),
                message: format!(
                    "the byte at offset {offset} is not UTF-8; expected a UTF-8 JSON file"
                ),
            }
        })?;
        Self::from_json_str(source, text)
    }

    /// The JSON text (pretty-printed, newline-terminated), after validation.
    pub fn to_json_string(&self, destination: &str) -> Result<String, IoError> {
        self.validate(destination)?;
        if self.psd_map.is_some() && self.version < 2 {
            return Err(IoError::Invalid {
                at: Location::file(destination),
                message: "a calibration with a PSD map needs calibration.json version 2".into(),
            });
        }
        let encoded = if self.version >= 2 {
            serde_json::to_string_pretty(&v2::FileV2::from_record(self))
        } else {
            serde_json::to_string_pretty(self)
        };
        let mut text = encoded.map_err(|e| IoError::Invalid {
            at: Location::file(destination),
            message: format!("cannot encode the calibration as JSON: {e}"),
        })?;
        text.push('\n');
        Ok(text)
    }
}

/// Reads and validates calibration.json.
pub fn read_calibration(path: impl AsRef<Path>) -> Result<Calibration, IoError> {
    read_calibration_with(path, ReadLimits::default())
}

/// [`read_calibration`] within `limits` (docs/formats.md, "Limits").
pub fn read_calibration_with(
    path: impl AsRef<Path>,
    limits: ReadLimits,
) -> Result<Calibration, IoError> {
    let path = path.as_ref();
    let source = path.display().to_string();
    let bytes = crate::limits::read_bounded(path, limits)?;
    Calibration::from_json_bytes(&source, &bytes)
}

/// Validates and writes calibration.json atomically.
pub fn write_calibration(path: impl AsRef<Path>, calibration: &Calibration) -> Result<(), IoError> {
    let path = path.as_ref();
    let text = calibration.to_json_string(&path.display().to_string())?;
    write_atomic_bytes(path, text.as_bytes())
}

/// The fields read before anything else.
#[derive(Deserialize)]
struct Header {
    #[serde(rename = "format", deserialize_with = "de_format")]
    _format: String,
    #[serde(rename = "version", deserialize_with = "de_version")]
    _version: u32,
}

/// The version of a psdcal calibration file newer than this one, if it is.
fn newer_version(text: &str) -> Option<u64> {
    let value: serde_json::Value = serde_json::from_str(text).ok()?;
    if value.get("format")?.as_str()? != CALIBRATION_FORMAT {
        return None;
    }
    let found = value.get("version")?.as_u64()?;
    (found > u64::from(CALIBRATION_VERSION)).then_some(found)
}
