//! Output shared by `aoa`, `locate` and `map`: tables whose unanswered rows
//! carry a `status` and empty values, the status count that the summary
//! line prints, per-row warnings, the calibrated sensor of a calibration
//! file, and the hints of psdcal-locate's errors.

use std::collections::BTreeMap;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use psdcal_io::{write_atomic, Calibration, IoError, Location, Points};
use psdcal_locate::{CalibratedSensor, LocateError, ParameterCovariance};

/// At most this many per-row warnings are printed.
const MAX_ROW_WARNINGS: usize = 20;

/// A number for a CSV field (shortest round-trip form; never NaN: a
/// non-finite value is written empty).
pub fn num(v: f64) -> String {
    if v.is_finite() {
        v.to_string()
    } else {
        String::new()
    }
}

/// Degrees of an angle in radians.
pub fn deg(rad: f64) -> String {
    num(rad.to_degrees())
}

/// `n` empty fields.
pub fn empty(n: usize) -> Vec<String> {
    vec![String::new(); n]
}

/// Writes a CSV table (header, rows) to `out`.
pub fn write_table<W: Write>(out: W, header: &[String], rows: &[Vec<String>]) -> io::Result<()> {
    let mut writer = csv::WriterBuilder::new().flexible(true).from_writer(out);
    writer.write_record(header)?;
    for row in rows {
        writer.write_record(row)?;
    }
    writer.flush()
}

/// The header and rows of `points` (every input column, text unchanged)
/// followed by the added columns.
pub fn points_table(
    points: &Points,
    added: &[String],
    values: Vec<Vec<String>>,
) -> (Vec<String>, Vec<Vec<String>>) {
    let header = points
        .header
        .iter()
        .cloned()
        .chain(added.iter().cloned())
        .collect();
    let rows = points
        .rows
        .iter()
        .zip(values)
        .map(|(row, extra)| row.fields.iter().cloned().chain(extra).collect())
        .collect();
    (header, rows)
}

/// Refuses input that already has a column the answer adds.
pub fn refuse_existing_columns(points: &Points, added: &[String]) -> Result<(), IoError> {
    if let Some(name) = added.iter().find(|name| points.has_column(name)) {
        return Err(IoError::Structure {
            at: Location::line(&points.source, points.header_line),
            message: format!(
                "the input already has a column '{name}', which the answer adds; expected input \
                 without the columns {}",
                added.join(", ")
            ),
        });
    }
    Ok(())
}

/// Writes the table to `out` atomically, or to standard output.
pub fn write_output(
    out: Option<&PathBuf>,
    header: &[String],
    rows: &[Vec<String>],
) -> anyhow::Result<()> {
    match out {
        Some(path) => Ok(write_atomic(path, |w| write_table(w, header, rows))?),
        None => {
            let mut stdout = io::stdout().lock();
            write_table(&mut stdout, header, rows)
                .and_then(|()| stdout.flush())
                .map_err(|source| {
                    IoError::Write {
                        file: "standard output".to_string(),
                        source,
                    }
                    .into()
                })
        }
    }
}

/// Counts of each status, and the warnings of the rows that are not `ok`.
#[derive(Debug, Default)]
pub struct StatusCount {
    counts: BTreeMap<String, usize>,
    rows: usize,
    answered: usize,
    warnings: Vec<String>,
}

impl StatusCount {
    /// Records an answered row (`status` is `ok` or caution codes).
    pub fn answered(&mut self, status: &str, warning: Option<String>) {
        self.rows += 1;
        self.answered += 1;
        for code in status.split(';') {
            *self.counts.entry(code.to_string()).or_default() += 1;
        }
        if let Some(w) = warning {
            self.warnings.push(w);
        }
    }

    /// Records a row without an answer.
    pub fn failed(&mut self, error: &LocateError, at: &str) {
        self.rows += 1;
        *self.counts.entry(error.status().to_string()).or_default() += 1;
        self.warnings.push(format!("{at}: {error}; no answer"));
    }

    /// Rows without an answer.
    pub fn unanswered(&self) -> usize {
        self.rows - self.answered
    }

    /// `12 ok, 1 off_active_area, 2 outside_valid_region (2 not answered)`.
    pub fn summary(&self) -> String {
        let mut parts: Vec<String> = Vec::new();
        if let Some(ok) = self.counts.get("ok") {
            parts.push(format!("{ok} ok"));
        }
        for (code, n) in &self.counts {
            if code != "ok" {
                parts.push(format!("{n} {code}"));
            }
        }
        let mut text = parts.join(", ");
        if self.unanswered() > 0 {
            text.push_str(&format!(" ({} not answered)", self.unanswered()));
        }
        text
    }

    /// The counts as JSON.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "rows": self.rows,
            "answered": self.answered,
            "not_answered": self.unanswered(),
            "status": self.counts,
        })
    }

    /// Prints the per-row warnings on standard error (at most 20).
    pub fn print_warnings(&self) {
        for w in self.warnings.iter().take(MAX_ROW_WARNINGS) {
            eprintln!("warning: {w}");
        }
        if self.warnings.len() > MAX_ROW_WARNINGS {
            eprintln!(
                "warning: {} more rows with a status other than ok (see the status column)",
                self.warnings.len() - MAX_ROW_WARNINGS
            );
        }
    }
}

/// The calibrated sensor of a calibration file: model, sensor size, gains
/// and covariance.
pub fn calibrated_sensor(
    calibration: &Calibration,
    file: &Path,
) -> Result<CalibratedSensor, IoError> {
    let covariance = ParameterCovariance::from_named(
        &calibration.covariance.parameters,
        &calibration.covariance.matrix,
    )
    .map_err(|e| IoError::Invalid {
        at: Location::file(&file.display().to_string()),
        message: format!("covariance: {e}"),
    })?;
    let mut sensor = CalibratedSensor::new(calibration.to_model(), calibration.geometry())
        .with_covariance(covariance);
    sensor.gains = calibration.gains();
    Ok(sensor)
}

/// A warning when a calibration has no covariance.
pub fn warn_without_covariance(sensor: &CalibratedSensor, file: &Path) {
    if sensor.covariance.is_empty() {
        eprintln!(
            "warning: {} has no covariance (nothing was estimated): the calibration's part of \
             every sigma is 0",
            file.display()
        );
    }
}

/// What the user can do about an error of this module's commands, if it is one.
pub fn hint(error: &anyhow::Error) -> Option<&'static str> {
    if let Some(e) = error.downcast_ref::<LocateError>() {
        return Some(match e {
            LocateError::InvalidInput { .. } | LocateError::NonFinite { .. } => {
                "change the options or the data as the message says"
            }
            LocateError::InvalidCovariance { .. } => "write the calibration again with psdcal",
            _ => "see 'psdcal locate --help'",
        });
    }
    match error.downcast_ref::<IoError>() {
        Some(IoError::Field { .. }) => {
            Some("correct that field of the rig file (format: README, section 'Rig files')")
        }
        _ => None,
    }
}
