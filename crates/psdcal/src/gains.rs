//! The electrical calibration: relative channel gains from records in
//! which all four channels carry the same current.

use std::path::Path;

use psdcal_calib::equal_current_gains;
use psdcal_io::{GainStd, GainsFile, PointInput, Points, GAINS_FORMAT};

use crate::error::{Error, Result};

/// How the gains are estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GainsMethod {
    /// All four channels carry the same current.
    #[default]
    EqualCurrent,
}

impl GainsMethod {
    /// The name written in gains.json.
    pub fn name(self) -> &'static str {
        match self {
            GainsMethod::EqualCurrent => "equal-current",
        }
    }
}

/// The gains.json record estimated from the amplitude records in `signals`.
pub fn estimate_gains(signals: &Path, method: GainsMethod) -> Result<GainsFile> {
    let points = Points::read(signals)?;
    let records: Vec<_> = points
        .rows
        .iter()
        .filter_map(|r| match r.input {
            PointInput::Amplitudes(a) => Some(a),
            PointInput::Position(_) => None,
        })
        .collect();
    if records.is_empty() {
        return Err(Error::Input(format!(
            "{}: no amplitude columns (vx1, vx2, vy1, vy2); the equal-current method needs \
             electrode amplitudes",
            signals.display()
        )));
    }
    let estimate = equal_current_gains(&records)?;
    Ok(GainsFile {
        format: GAINS_FORMAT.into(),
        version: 1,
        method: method.name().to_string(),
        x2: estimate.gains.x2,
        y1: estimate.gains.y1,
        y2: estimate.gains.y2,
        std: GainStd {
            g_x2: estimate.std[0],
            g_y1: estimate.std[1],
            g_y2: estimate.std[2],
        },
        records: estimate.records,
    })
}
