//! truth.json: everything true about a simulated data set, written by
//! `psdcal simulate` beside its CSV files so that a calibration can be judged
//! against it. A JSON object, versioned like calibration.json:
//! `format` = `"psdcal-truth"`, `version` = 1; the simulation's settings
//! (seed, lens, SNR, switches, signal chain); the sensor size; the true
//! intrinsics and distortion (same names as calibration.json); the true
//! channel gains (relative to x1, and x1's absolute gain in V/A); and each
//! image's true pose (`rvec`, `t_mm`, `sensor_from_template`).

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::atomic::write_atomic_bytes;
use crate::limits::ReadLimits;
use crate::IoError;

/// The format name of truth.json.
pub const TRUTH_FORMAT: &str = "psdcal-truth";
/// The version written.
pub const TRUTH_VERSION: u32 = 1;

/// The settings a data set was simulated with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimulationSettings {
    /// Seed of every random draw.
    pub seed: u64,
    /// The paper's lens (1 or 2).
    pub lens: u8,
    /// Per-channel SNR, dB (`null`: no noise).
    pub snr_db: Option<f64>,
    /// Gain imbalance switched on.
    pub imbalance: bool,
    /// PSD distortion switched on.
    pub psd_distortion: bool,
    /// The PSD's non-radial non-linearity switched on (absent in older files).
    #[serde(default)]
    pub psd_nonlinearity: bool,
    /// Template name.
    pub template: String,
    /// Number of images.
    pub images: usize,
    /// LED spot photocurrent, A.
    pub photocurrent_a: f64,
    /// Modulation frequency, Hz.
    pub f0_hz: f64,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Band-pass bandwidth, Hz.
    pub bandwidth_hz: f64,
    /// Band-pass order.
    pub filter_order: usize,
    /// Record length, s.
    pub record_s: f64,
    /// Demodulation method.
    pub demodulation: String,
}

/// The true channel gains.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrueGains {
    /// Absolute transimpedance gain of channel x1 at f0, V/A.
    pub x1_v_per_a: f64,
    /// Gain of x2 relative to x1.
    pub x2: f64,
    /// Gain of y1 relative to x1.
    pub y1: f64,
    /// Gain of y2 relative to x1.
    pub y2: f64,
}

/// One image's true pose.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruePose {
    /// Image id.
    pub id: String,
    /// Rodrigues vector of `sensor_from_template`, rad.
    pub rvec: [f64; 3],
    /// Translation of `sensor_from_template`, mm.
    pub t_mm: [f64; 3],
}

/// truth.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// `"psdcal-truth"`.
    pub format: String,
    /// 1.
    pub version: u32,
    /// How it was simulated.
    pub simulation: SimulationSettings,
    /// Sensor size.
    pub sensor: crate::SensorSize,
    /// True intrinsics.
    pub intrinsics: crate::IntrinsicsRecord,
    /// True distortion (`l1` non-zero with PSD distortion).
    pub distortion: psdcal_model::Distortion,
    /// True gains.
    pub gains: TrueGains,
    /// True poses.
    pub images: Vec<TruePose>,
}

/// Writes truth.json atomically.
pub fn write_truth(path: impl AsRef<Path>, truth: &Truth) -> Result<(), IoError> {
    let path = path.as_ref();
    let mut text = serde_json::to_string_pretty(truth).map_err(|e| IoError::Invalid {
        at: crate::Location::file(&path.display().to_string()),
        message: format!("cannot encode the truth as JSON: {e}"),
    })?;
    text.push('\n');
    write_atomic_bytes(path, text.as_bytes())
}

/// Reads truth.json.
pub fn read_truth(path: impl AsRef<Path>) -> Result<Truth, IoError> {
    read_truth_with(path, ReadLimits::default())
}

/// [`read_truth`] within `limits` (docs/formats.md, "Limits").
pub fn read_truth_with(path: impl AsRef<Path>, limits: ReadLimits) -> Result<Truth, IoError> {
    let path = path.as_ref();
    let source = path.display().to_string();
    let text = crate::limits::read_text(path, limits)?;
    let truth: Truth =
        serde_json::from_str(&text).map_err(|e| crate::error::json_error(&source, &e))?;
    if truth.format != TRUTH_FORMAT {
        return Err(IoError::Invalid {
            at: crate::Location::file(&source),
            message: format!(
                "expected format \"{TRUTH_FORMAT}\", found \"{}\"",
                crate::limits::excerpt(&truth.format).escape_debug()
            ),
        });
    }
    Ok(truth)
}
