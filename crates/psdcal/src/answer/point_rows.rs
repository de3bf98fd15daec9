//! The per-point answers of `correct`, `aoa` and `locate` on a plane,
//! streamed: points.csv is read one row at a time and each answered row is
//! written at once (to a same-folder temporary file renamed at the end, or
//! to standard output), so memory stays flat whatever the input's size.
//!
//! Every row is answered: its input columns (text unchanged), the command's
//! added columns, then `status`. A row the command answers gets `ok` or its
//! cautions; a row it cannot answer gets empty values and the
//! [`LocateError::status`] code of its error (`non_finite_input` for an
//! empty or non-finite cell, `no_light`, `outside_valid_region`,
//! `non_finite_answer` when a computed value is not finite, …), and the
//! batch goes on: no row is `ok` with an empty cell.

use std::io::{self, Write};
use std::path::Path;

use psdcal_io::{write_atomic, IoError, Location, PointInput, PointStream};
use psdcal_locate::{Caution, LocateError, Measurement};

use crate::base::error::{Error, Result};
use crate::base::summary::{path_json, Summary};
use crate::base::table::{empty, StatusCount};

/// What a streamed answer wrote.
#[derive(Debug, Clone)]
pub struct PointsAnswer {
    /// The points file, as named in messages.
    pub source: String,
    /// Whether the rows gave amplitudes.
    pub amplitudes: bool,
    /// Rows answered.
    pub rows: usize,
    /// The columns added, in order (the last is `status`).
    pub added: Vec<String>,
    /// Status counts and the first per-row warnings.
    pub count: StatusCount,
}

impl PointsAnswer {
    /// The summary of a points command (`aoa`, `correct`): the line
    /// `<verb> N point(s) of <points> with <calibration>: <status counts>`
    /// (naming the added columns when `name_columns`), the JSON with the
    /// command's own fields `extra` (an object) merged in, and the rows'
    /// warnings.
    pub fn summary(
        &self,
        command: &str,
        verb: &str,
        calibration: &Path,
        out: Option<&Path>,
        extra: serde_json::Value,
        name_columns: bool,
    ) -> Summary {
        let line = format!(
            "{verb} {} point{} of {} with {}: {}",
            self.rows,
            if self.rows == 1 { "" } else { "s" },
            self.source,
            calibration.display(),
            self.count.summary()
        );
        let mut json = serde_json::json!({
            "command": command,
            "calibration": calibration.display().to_string(),
            "points": self.source,
            "out": path_json(out),
            "from_amplitudes": self.amplitudes,
            "added_columns": self.added,
            "rows": self.count.to_json(),
        });
        if let (Some(map), Some(extra)) = (json.as_object_mut(), extra.as_object()) {
            map.extend(extra.clone());
        }
        let summary = Summary::new(line, json)
            .table_at(out)
            .warn(self.count.warning_lines());
        match out {
            Some(_) if name_columns => Summary {
                text: format!(
                    "{} (added {})\n",
                    summary.text.trim_end(),
                    self.added.join(", ")
                ),
                ..summary
            },
            _ => summary,
        }
    }
}

/// The values of one answered row (without `status`) and its cautions, or
/// why it has no answer.
pub type RowAnswer = std::result::Result<(Vec<String>, Vec<Caution>), LocateError>;

/// An answered row with a blank value (a number that came out NaN or
/// infinite) is no answer: never `ok` with an empty cell.
fn refuse_blank(
    answer: (Vec<String>, Vec<Caution>),
) -> std::result::Result<(Vec<String>, Vec<Caution>), LocateError> {
    if answer.0.iter().any(String::is_empty) {
        Err(LocateError::NonFiniteAnswer {
            what: "a value of the row",
        })
    } else {
        Ok(answer)
    }
}

/// Streams `points` to `out` (standard output when `None`): `added` gives
/// the added columns from whether the input has amplitudes (ending with
/// `status`); `answer` computes one row.
pub fn answer_points(
    points: &Path,
    out: Option<&Path>,
    added: impl FnOnce(bool) -> Vec<String>,
    mut answer: impl FnMut(&Measurement) -> RowAnswer,
) -> Result<PointsAnswer> {
    let mut stream = PointStream::open(points)?;
    if out.is_none() {
        // Standard output cannot be taken back: a file that fails on a
        // later row must fail before the first row is printed (a second
        // pass, still in constant memory).
        let mut check = PointStream::open(points)?;
        while check.next_row()?.is_some() {}
    }
    let added = added(stream.amplitudes);
    if let Some(name) = added.iter().find(|name| stream.has_column(name)) {
        return Err(IoError::Structure {
            at: Location::line(stream.source(), stream.header_line()),
            message: format!(
                "the input already has a column '{name}', which the answer adds; expected input \
                 without the columns {}",
                added.join(", ")
            ),
        }
        .into());
    }
    let mut count = StatusCount::default();
    let mut rows = 0;
    let mut failure: Option<Error> = None;
    let mut write = |w: &mut dyn Write| -> io::Result<()> {
        let mut writer = csv::WriterBuilder::new().flexible(true).from_writer(w);
        let header = stream.header().iter().chain(added.iter());
        writer.write_record(header)?;
        loop {
            let row = match stream.next_row() {
                Ok(Some(row)) => row,
                Ok(None) if rows == 0 => {
                    failure = Some(
                        IoError::Structure {
                            at: Location::line(stream.source(), stream.header_line()),
                            message: "the file has a header but no data rows; expected at least \
                                      one row after it"
                                .to_string(),
                        }
                        .into(),
                    );
                    return Err(io::Error::other("the input has no rows"));
                }
                Ok(None) => break,
                Err(e) => {
                    failure = Some(e.into());
                    return Err(io::Error::other("the input failed"));
                }
            };
            rows += 1;
            let at = format!("{}:{}", stream.source(), row.line_no);
            let result = match &row.input {
                PointInput::Position(p) => answer(&Measurement::Point(*p)),
                PointInput::Amplitudes(a) => answer(&Measurement::Amplitudes(*a)),
                _ => Err(LocateError::NonFinite { what: "input cell" }),
            }
            .and_then(refuse_blank);
            let mut fields = row.fields;
            match result {
                Ok((values, cautions)) => {
                    fields.extend(values);
                    fields.push(count.answered_with(&at, &cautions));
                }
                Err(e) => {
                    fields.extend(empty(added.len() - 1));
                    fields.push(e.status().to_string());
                    let at = match &row.input {
                        PointInput::NonFinite { column, message } => {
                            format!("{at}: {column}: {message}")
                        }
                        _ => at,
                    };
                    count.failed(&e, &at);
                }
            }
            writer.write_record(&fields)?;
        }
        writer.flush()
    };
    let written = match out {
        Some(path) => write_atomic(path, |w| write(w)),
        None => crate::base::stdout::write_stdout(write),
    };
    if let Some(e) = failure {
        return Err(e);
    }
    written?;
    Ok(PointsAnswer {
        source: stream.source().to_string(),
        amplitudes: stream.amplitudes,
        rows,
        added,
        count,
    })
}
