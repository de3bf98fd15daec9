//! The electrical calibration: relative channel gains from records in
//! which all four channels carry the same current.

use std::path::Path;

use psdcal_calib::equal_current_gains;
use psdcal_io::{
    shown_number, GainStd, GainsFile, IoError, Location, PointInput, Points, GAINS_FORMAT,
};
use psdcal_model::Amplitudes;

use crate::base::error::{Error, Result};
use crate::base::summary::Summary;

/// How the gains are estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GainsMethod {
    /// All four channels carry the same current.
    #[default]
    EqualCurrent,
}

#[cfg(feature = "clap")]
impl clap::ValueEnum for GainsMethod {
    fn value_variants<'a>() -> &'a [Self] {
        &[GainsMethod::EqualCurrent]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

impl GainsMethod {
    /// The name written in gains.json.
    pub fn name(self) -> &'static str {
        match self {
            GainsMethod::EqualCurrent => "equal-current",
        }
    }
}

/// The largest ratio (or its inverse) between two amplitudes of one
/// equal-current record: the channels carry the same current, so their
/// amplitudes differ only by the amplifier gains.
pub const MAX_GAIN_RATIO: f64 = 10.0;

/// The summary of gains estimated from `signals` (and written to `out`):
/// each gain with its σ; the JSON is gains.json itself.
pub fn gains_summary(file: &GainsFile, signals: &Path, out: Option<&Path>) -> Result<Summary> {
    let json = serde_json::to_value(file)
        .map_err(|e| Error::Input(format!("cannot encode the gains: {e}")))?;
    let mut text = format!(
        "gains relative to x1 from {} equal-current records ({}):\n",
        file.records,
        signals.display()
    );
    for (name, g, s) in [
        ("g_x2", file.x2, file.std.g_x2),
        ("g_y1", file.y1, file.std.g_y1),
        ("g_y2", file.y2, file.std.g_y2),
    ] {
        text.push_str(&format!("  {name} = {g:.8} ± {s:.2e}\n"));
    }
    Ok(Summary::new(text, json).wrote(out))
}

/// The gains.json record estimated from the amplitude records in `signals`.
/// Every record must have four positive amplitudes within a factor
/// `MAX_GAIN_RATIO` (10) of `vx1`; a record that does not is an error naming
/// its line, so the file written is always one `calibrate --gains` reads.
/// `signals` is read whole, within `limits`.
pub fn estimate_gains(
    signals: &Path,
    method: GainsMethod,
    limits: psdcal_io::ReadLimits,
) -> Result<GainsFile> {
    let points = Points::read_with(signals, limits)?;
    if !points.amplitudes {
        return Err(Error::Input(format!(
            "{}: no amplitude columns (vx1, vx2, vy1, vy2); the equal-current method needs \
             electrode amplitudes",
            signals.display()
        )));
    }
    let mut records = Vec::with_capacity(points.rows.len());
    for row in &points.rows {
        let PointInput::Amplitudes(a) = row.input else {
            continue;
        };
        check_record(&points.source, row.line_no, &a)?;
        records.push(a);
    }
    let estimate = equal_current_gains(&records).map_err(|e| {
        Error::Input(format!(
            "{}: {e}; expected equal-current records with four positive amplitudes",
            points.source
        ))
    })?;
    let file = GainsFile {
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
    };
    if !file.is_finite() {
        return Err(Error::Input(format!(
            "{}: the records give no finite gains; expected equal-current records with \
             amplitudes of the same order",
            points.source
        )));
    }
    Ok(file)
}

/// Checks one equal-current record: four positive amplitudes within a
/// factor [`MAX_GAIN_RATIO`] of `vx1`.
fn check_record(source: &str, line: usize, a: &Amplitudes) -> Result<()> {
    let at = |message: String| {
        Error::Io(IoError::Invalid {
            at: Location::line(source, line),
            message,
        })
    };
    let values = [
        ("vx1", a.vx1),
        ("vx2", a.vx2),
        ("vy1", a.vy1),
        ("vy2", a.vy2),
    ];
    if let Some((name, v)) = values.iter().find(|(_, v)| v.is_nan() || *v <= 0.0) {
        return Err(at(format!(
            "amplitude {name} = {}; expected four positive amplitudes in an equal-current \
             record",
            shown_number(*v)
        )));
    }
    for (name, v) in &values[1..] {
        let ratio = v / a.vx1;
        if !(1.0 / MAX_GAIN_RATIO..=MAX_GAIN_RATIO).contains(&ratio) {
            return Err(at(format!(
                "{name}/vx1 = {} is an outlier: the channels of an equal-current record carry \
                 the same current, so their amplitudes agree within a factor {MAX_GAIN_RATIO}; \
                 remove or correct this record",
                shown_number(ratio)
            )));
        }
    }
    Ok(())
}
