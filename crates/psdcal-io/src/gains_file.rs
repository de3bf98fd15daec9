//! gains.json: relative channel gains from an electrical calibration
//! (`psdcal gains`), to be held fixed by `psdcal calibrate --gains`. A JSON
//! object: `format` = `"psdcal-gains"`, `version` = 1, `method`, the gains
//! of channels x2, y1, y2 relative to x1 (`x2`, `y1`, `y2`), their standard
//! deviations (`std`: `g_x2`, `g_y1`, `g_y2`) and the number of `records`.

use std::path::Path;

use psdcal_model::ChannelGains;
use serde::{Deserialize, Serialize};

use crate::atomic::write_atomic_bytes;
use crate::limits::ReadLimits;
use crate::{IoError, Location};

/// The format name of gains.json.
pub const GAINS_FORMAT: &str = "psdcal-gains";

/// Standard deviations of the three relative gains.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GainStd {
    /// σ of `g_x2`.
    pub g_x2: f64,
    /// σ of `g_y1`.
    pub g_y1: f64,
    /// σ of `g_y2`.
    pub g_y2: f64,
}

/// gains.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GainsFile {
    /// `"psdcal-gains"`.
    pub format: String,
    /// 1.
    pub version: u32,
    /// How the gains were estimated (`equal-current`).
    pub method: String,
    /// Gain of x2 relative to x1.
    pub x2: f64,
    /// Gain of y1 relative to x1.
    pub y1: f64,
    /// Gain of y2 relative to x1.
    pub y2: f64,
    /// Their standard deviations.
    pub std: GainStd,
    /// Records used.
    pub records: usize,
}

impl GainsFile {
    /// The gains.
    pub fn gains(&self) -> ChannelGains {
        ChannelGains {
            x2: self.x2,
            y1: self.y1,
            y2: self.y2,
        }
    }

    /// Whether the gains and their standard deviations are all finite.
    pub fn is_finite(&self) -> bool {
        let s = &self.std;
        [self.x2, self.y1, self.y2, s.g_x2, s.g_y1, s.g_y2]
            .iter()
            .all(|v| v.is_finite())
    }
}

/// Writes gains.json atomically.
pub fn write_gains(path: impl AsRef<Path>, file: &GainsFile) -> Result<(), IoError> {
    let path = path.as_ref();
    if !file.is_finite() || file.gains().validate().is_err() {
        return Err(IoError::Invalid {
            at: Location::file(&path.display().to_string()),
            message: "the gains or their standard deviations are not positive finite numbers; \
                      nothing was written"
                .to_string(),
        });
    }
    let mut text = serde_json::to_string_pretty(file).map_err(|e| IoError::Invalid {
        at: Location::file(&path.display().to_string()),
        message: format!("cannot encode the gains as JSON: {e}"),
    })?;
    text.push('\n');
    write_atomic_bytes(path, text.as_bytes())
}

/// Reads and checks gains.json.
pub fn read_gains(path: impl AsRef<Path>) -> Result<GainsFile, IoError> {
    read_gains_with(path, ReadLimits::default())
}

/// [`read_gains`] within `limits` (docs/formats.md, "Limits").
pub fn read_gains_with(path: impl AsRef<Path>, limits: ReadLimits) -> Result<GainsFile, IoError> {
    let path = path.as_ref();
    let source = path.display().to_string();
    GainsFile::from_json_str(&source, &crate::limits::read_text(path, limits)?)
}

impl GainsFile {
    /// Reads and checks gains.json from a reader; `source` names it in
    /// messages.
    pub fn from_reader(source: &str, reader: impl std::io::Read) -> Result<Self, IoError> {
        Self::from_reader_with(source, reader, ReadLimits::default())
    }

    /// [`Self::from_reader`] within `limits` (docs/formats.md, "Limits").
    pub fn from_reader_with(
        source: &str,
        reader: impl std::io::Read,
        limits: ReadLimits,
    ) -> Result<Self, IoError> {
        Self::from_json_str(
            source,
            &crate::limits::read_text_from(source, reader, limits)?,
        )
    }

    /// Checks gains.json text; `source` names it in messages.
    pub fn from_json_str(source: &str, text: &str) -> Result<Self, IoError> {
        check_gains(source, text)
    }
}

fn check_gains(source: &str, text: &str) -> Result<GainsFile, IoError> {
    let file: GainsFile =
        serde_json::from_str(text).map_err(|e| crate::error::json_error(source, &e))?;
    if file.format != GAINS_FORMAT {
        return Err(IoError::Invalid {
            at: Location::file(source),
            message: format!(
                "expected format \"{GAINS_FORMAT}\", found \"{}\"",
                crate::limits::excerpt(&file.format).escape_debug()
            ),
        });
    }
    if file.version > 1 {
        return Err(IoError::Invalid {
            at: Location::file(source),
            message: format!(
                "gains file version {} was written by a newer psdcal; upgrade psdcal",
                file.version
            ),
        });
    }
    file.gains().validate().map_err(|e| IoError::Invalid {
        at: Location::file(source),
        message: e.to_string(),
    })?;
    Ok(file)
}
