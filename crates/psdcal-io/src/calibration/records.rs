//! The parts of calibration.json (see the parent module for the format):
//! sensor size, intrinsics, gains, standard deviations, covariance, fit
//! summary and per-image poses. Values that must be valid in any file are
//! checked while parsing, so that errors carry the JSON line and column.

use std::fmt;

use nalgebra::Vector3;
use psdcal_model::{ChannelGains, CovarianceError, ParameterCovariance, Pose};
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::ser::Serializer;
use serde::{Deserialize, Serialize};

use super::rules::{de_identifier, de_positive, shown};

/// The program that wrote a calibration.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Software {
    /// Program name.
    pub name: String,
    /// Program version.
    pub version: String,
}

impl Software {
    /// This psdcal.
    pub fn current() -> Self {
        Self {
            name: "psdcal".to_string(),
            version: env!("CARGO_PKG_VERSION").to_string(),
        }
    }
}

/// Active area of the PSD, mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SensorSize {
    /// Side along x, mm.
    #[serde(deserialize_with = "de_positive")]
    pub lx_mm: f64,
    /// Side along y, mm.
    #[serde(deserialize_with = "de_positive")]
    pub ly_mm: f64,
}

/// Pinhole intrinsics with their units in the names (docs/model.md §3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct IntrinsicsRecord {
    /// Focal length, mm, positive.
    #[serde(deserialize_with = "de_positive")]
    pub f_mm: f64,
    /// Optical centre x, mm.
    pub cx_mm: f64,
    /// Optical centre y, mm.
    pub cy_mm: f64,
    /// Skew `γ`, mm.
    pub skew: f64,
}

/// Channel gains of an electrical calibration (docs/model.md §1). Only the ratios
/// to `x1` matter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "GainsFields")]
pub struct GainsRecord {
    /// Gain of channel x1 (the reference, normally 1).
    pub x1: f64,
    /// Gain of channel x2.
    pub x2: f64,
    /// Gain of channel y1.
    pub y1: f64,
    /// Gain of channel y2.
    pub y2: f64,
    /// Whether the fit estimated the gains (then `std` has `g_x2`, `g_y1`, `g_y2`).
    pub estimated: bool,
}

#[derive(Deserialize)]
struct GainsFields {
    x1: f64,
    x2: f64,
    y1: f64,
    y2: f64,
    estimated: bool,
}

impl TryFrom<GainsFields> for GainsRecord {
    type Error = String;
    fn try_from(f: GainsFields) -> Result<Self, String> {
        let record = GainsRecord {
            x1: f.x1,
            x2: f.x2,
            y1: f.y1,
            y2: f.y2,
            estimated: f.estimated,
        };
        record.check()?;
        Ok(record)
    }
}

impl GainsRecord {
    /// A record of relative gains (`x1 = 1`).
    pub fn new(gains: &ChannelGains, estimated: bool) -> Self {
        Self {
            x1: 1.0,
            x2: gains.x2,
            y1: gains.y1,
            y2: gains.y2,
            estimated,
        }
    }

    /// The gains relative to channel x1.
    pub fn to_gains(&self) -> ChannelGains {
        ChannelGains::from_absolute(self.x1, self.x2, self.y1, self.y2)
    }

    pub(super) fn check(&self) -> Result<(), String> {
        for (name, value) in [
            ("x1", self.x1),
            ("x2", self.x2),
            ("y1", self.y1),
            ("y2", self.y2),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(format!(
                    "gains.{name} must be a positive number, found {}",
                    shown(value)
                ));
            }
        }
        Ok(())
    }
}

/// Standard deviations by parameter name, in file order (a JSON object).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StdDevs(pub Vec<(String, f64)>);

impl StdDevs {
    /// Reorders the entries as `names` lists them, when `names` holds
    /// exactly the entries' names (otherwise leaves them for validation to
    /// refuse).
    pub fn order_as(&mut self, names: &[String]) {
        if names.len() != self.0.len() {
            return;
        }
        let ordered: Option<Vec<(String, f64)>> = names
            .iter()
            .map(|n| self.0.iter().find(|(m, _)| m == n).cloned())
            .collect();
        if let Some(ordered) = ordered {
            self.0 = ordered;
        }
    }

    /// The standard deviation of `name`.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }

    /// The names, in order.
    pub fn names(&self) -> Vec<&str> {
        self.0.iter().map(|(n, _)| n.as_str()).collect()
    }
}

impl Serialize for StdDevs {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_map(self.0.iter().map(|(k, v)| (k, v)))
    }
}

impl<'de> Deserialize<'de> for StdDevs {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct StdVisitor;
        impl<'de> Visitor<'de> for StdVisitor {
            type Value = StdDevs;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an object of standard deviations by parameter name")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<StdDevs, A::Error> {
                let mut entries: Vec<(String, f64)> = Vec::new();
                while let Some((name, value)) = map.next_entry::<String, f64>()? {
                    if entries.iter().any(|(n, _)| *n == name) {
                        return Err(de::Error::custom(format!(
                            "std names parameter '{name}' twice; expected each once"
                        )));
                    }
                    if value < 0.0 {
                        return Err(de::Error::custom(format!(
                            "std.{name} must be zero or positive, found {}",
                            shown(value)
                        )));
                    }
                    entries.push((name, value));
                }
                Ok(StdDevs(entries))
            }
        }
        deserializer.deserialize_map(StdVisitor)
    }
}

/// Covariance of the estimated parameters.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(try_from = "CovarianceFields")]
pub struct Covariance {
    /// Row and column names (as in `std`).
    pub parameters: Vec<String>,
    /// Square symmetric matrix, one row per parameter.
    pub matrix: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct CovarianceFields {
    parameters: Vec<String>,
    matrix: Vec<Vec<f64>>,
}

impl TryFrom<CovarianceFields> for Covariance {
    type Error = String;
    fn try_from(f: CovarianceFields) -> Result<Self, String> {
        let c = Covariance {
            parameters: f.parameters,
            matrix: f.matrix,
        };
        c.check()?;
        Ok(c)
    }
}

impl Covariance {
    /// The entry for parameters `a` and `b`.
    pub fn get(&self, a: &str, b: &str) -> Option<f64> {
        let i = self.parameters.iter().position(|p| p == a)?;
        let j = self.parameters.iter().position(|p| p == b)?;
        self.matrix.get(i)?.get(j).copied()
    }

    /// The covariance as psdcal-model's [`ParameterCovariance`] (validated
    /// there; the error phrased with this record's field names).
    pub fn to_parameter_covariance(&self) -> Result<ParameterCovariance, String> {
        ParameterCovariance::from_named(&self.parameters, &self.matrix).map_err(|e| {
            let n = self.parameters.len();
            match e {
                CovarianceError::Shape { rows, .. } => format!(
                    "covariance.matrix has {rows} rows for {n} parameters; expected a square {n} \
                     x {n} matrix"
                ),
                CovarianceError::RowLength { row, len, .. } => format!(
                    "covariance.matrix row {} has {len} entries; expected {n}",
                    row + 1
                ),
                CovarianceError::Duplicate { name } => {
                    format!("covariance.parameters lists '{name}' twice; expected each once")
                }
                CovarianceError::NonFinite { row, col } => {
                    format!("covariance.matrix[{row}][{col}] must be a finite number")
                }
                CovarianceError::Asymmetric {
                    row,
                    col,
                    value,
                    mirror,
                } => format!(
                    "covariance.matrix is not symmetric: [{row}][{col}] = {value} but \
                     [{col}][{row}] = {mirror}"
                ),
                CovarianceError::NegativeVariance { index, value, .. } => format!(
                    "covariance.matrix[{index}][{index}] is a variance and must not be negative, \
                     found {value}"
                ),
                other => format!("covariance: {other}"),
            }
        })
    }

    pub(super) fn check(&self) -> Result<(), String> {
        self.to_parameter_covariance().map(|_| ())
    }

    /// Refuses a matrix that is not positive semi-definite: the smallest
    /// eigenvalue of its correlation matrix `D^-1/2 C D^-1/2` (scale-free:
    /// the parameters' units differ by many orders) must not be below
    /// `-1e-6` (the rounding of a computed covariance); a zero variance
    /// needs a zero row.
    pub(super) fn check_positive_semidefinite(&self) -> Result<(), String> {
        let n = self.parameters.len();
        if n == 0 {
            return Ok(());
        }
        let scale: Vec<f64> = (0..n).map(|i| self.matrix[i][i].sqrt()).collect();
        for (i, row) in self.matrix.iter().enumerate() {
            if let Some((j, v)) = row.iter().enumerate().find(|(_, v)| **v != 0.0) {
                if scale[i] == 0.0 {
                    return Err(format!(
                        "covariance.matrix[{i}][{j}] is {} but '{}' has variance 0; expected a \
                         positive semi-definite matrix",
                        shown(*v),
                        self.parameters[i]
                    ));
                }
            }
        }
        let unit = |i: usize| if scale[i] > 0.0 { scale[i] } else { 1.0 };
        let correlation =
            nalgebra::DMatrix::from_fn(n, n, |i, j| self.matrix[i][j] / unit(i) / unit(j));
        let smallest = correlation
            .symmetric_eigenvalues()
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        if smallest.is_nan() || smallest < -PSD_TOLERANCE {
            return Err(format!(
                "covariance.matrix is not positive semi-definite (its correlation matrix has the \
                 eigenvalue {}); expected a covariance as psdcal writes it (was it edited?)",
                shown(smallest)
            ));
        }
        Ok(())
    }
}

/// The most negative eigenvalue of a covariance's correlation matrix
/// accepted (rounding).
const PSD_TOLERANCE: f64 = 1e-6;

impl From<&ParameterCovariance> for Covariance {
    /// The record of a covariance: its names and (symmetric) rows.
    fn from(c: &ParameterCovariance) -> Self {
        Self {
            parameters: c.names().to_vec(),
            matrix: c.rows(),
        }
    }
}

/// Which error the fit minimised (docs/model.md §4.6): psdcal-model's
/// [`psdcal_model::CostKind`], the one definition the calibration uses too.
pub use psdcal_model::CostKind;

/// Summary of the fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitSummary {
    /// The minimised cost.
    pub cost: CostKind,
    /// The noise model that weighted the cost (`uniform`: unweighted, the
    /// paper's; `channel-snr`; `channel-floor`). Files written before it
    /// existed read as `uniform`.
    #[serde(default = "uniform_noise")]
    pub noise: String,
    /// Sum of squared template-plane errors, mm².
    pub residual_mm2: f64,
    /// RMS template-plane error, mm.
    pub rms_template_mm: f64,
    /// RMS image-plane error, mm.
    pub rms_image_mm: f64,
    /// Iterations of the optimiser.
    pub iterations: usize,
    /// Points used.
    pub points: usize,
    /// Images used.
    pub images: usize,
    /// Why the optimiser stopped.
    pub termination: String,
    /// How the covariance was estimated (docs/model.md §4.6): `linear`
    /// (`σ² (JᵀJ)⁻¹`), `sandwich` (the unweighted template-plane fit's,
    /// point noise propagated), `jackknife` (the analytic σ raised to the
    /// jackknife over images where that is larger) or `bootstrap`. Files written before it
    /// existed read as `linear`.
    #[serde(default = "linear_uncertainty")]
    pub uncertainty: String,
    /// The bootstrap's resamples and base seed, when `uncertainty` is `bootstrap`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bootstrap: Option<BootstrapRecord>,
    /// How the estimated parameters were chosen, when `calibrate` chose
    /// them by held-out error (docs/model.md §4.8): `{"rule", "candidates":
    /// [{"free", "held_out_rms_deg", "difference_deg2",
    /// "standard_error_deg2", "accepted"}], "chosen"}`; absent for a fit of
    /// given parameters.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_choice: Option<serde_json::Value>,
}

/// The bootstrap behind a covariance (calibration.json's `fit.bootstrap`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct BootstrapRecord {
    /// Resamples asked for.
    pub resamples: usize,
    /// Resamples whose refit failed (left out).
    pub failed: usize,
    /// Base seed (resample `b` from `ChaCha8Rng::seed_from_u64(seed + b)`).
    pub seed: u64,
}

fn linear_uncertainty() -> String {
    "linear".to_string()
}

impl Default for FitSummary {
    fn default() -> Self {
        Self {
            cost: CostKind::Template,
            noise: uniform_noise(),
            residual_mm2: 0.0,
            rms_template_mm: 0.0,
            rms_image_mm: 0.0,
            iterations: 0,
            points: 0,
            images: 0,
            termination: "not fitted".to_string(),
            uncertainty: linear_uncertainty(),
            bootstrap: None,
            model_choice: None,
        }
    }
}

fn uniform_noise() -> String {
    "uniform".to_string()
}

/// One image's pose and error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImageFit {
    /// Image identifier (text; a JSON integer is read as its text).
    #[serde(deserialize_with = "de_identifier")]
    pub id: String,
    /// Rodrigues vector of the sensor-from-template rotation, rad.
    pub rvec: [f64; 3],
    /// Sensor-from-template translation, mm.
    pub t_mm: [f64; 3],
    /// RMS error of the image's points, mm.
    pub rms_mm: f64,
    /// Points used.
    pub points: usize,
}

impl ImageFit {
    /// The record of a pose.
    pub fn new(id: &str, pose: &Pose, rms_mm: f64, points: usize) -> Self {
        Self {
            id: id.to_string(),
            rvec: [pose.rvec.x, pose.rvec.y, pose.rvec.z],
            t_mm: [pose.t.x, pose.t.y, pose.t.z],
            rms_mm,
            points,
        }
    }

    /// The sensor-from-template pose.
    pub fn pose(&self) -> Pose {
        Pose::new(Vector3::from(self.rvec), Vector3::from(self.t_mm))
    }
}
