//! The tables `aoa`, `locate` and `map` answer with: CSV rows whose
//! unanswered rows carry a `status` and empty values, and the count of
//! each status with a warning per row that is not `ok`.

use std::collections::BTreeMap;
use std::io::{self, Write};
use std::path::Path;

use psdcal_io::write_atomic;
use psdcal_locate::{status_of, Caution, LocateError};

use crate::base::error::Result;
use crate::base::stdout::write_stdout;

/// A CSV table.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Rows of fields.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// Writes the table as CSV.
    pub fn write_csv<W: Write>(&self, out: W) -> io::Result<()> {
        let mut writer = csv::WriterBuilder::new().flexible(true).from_writer(out);
        writer.write_record(&self.header)?;
        for row in &self.rows {
            writer.write_record(row)?;
        }
        writer.flush()
    }

    /// Writes the table to `out` atomically, or to standard output.
    pub fn write_to(&self, out: Option<&Path>) -> Result<()> {
        match out {
            Some(path) => Ok(write_atomic(path, |w| self.write_csv(w))?),
            None => Ok(write_stdout(|out| self.write_csv(out))?),
        }
    }
}

/// A number for a CSV field (shortest round-trip form; a non-finite value
/// is written empty, never NaN).
pub fn num(v: f64) -> String {
    psdcal_io::number_text(v)
}

/// Degrees of an angle in radians, for a CSV field.
pub fn deg(rad: f64) -> String {
    num(rad.to_degrees())
}

/// `n` empty fields.
pub fn empty(n: usize) -> Vec<String> {
    vec![String::new(); n]
}

/// At most this many per-row warnings are kept (the others are counted).
pub const MAX_ROW_WARNINGS: usize = 20;

/// Counts of each status, and the warnings of the first rows that are not
/// `ok` (at most [`MAX_ROW_WARNINGS`], so memory stays flat).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StatusCount {
    counts: BTreeMap<String, usize>,
    rows: usize,
    answered: usize,
    not_ok: usize,
    /// One line per row that is not `ok`, for the first of them.
    pub warnings: Vec<String>,
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
            self.warn(w);
        }
    }

    fn warn(&mut self, warning: String) {
        self.not_ok += 1;
        if self.warnings.len() < MAX_ROW_WARNINGS {
            self.warnings.push(warning);
        }
    }

    /// The rows' warnings as lines: the first [`MAX_ROW_WARNINGS`] kept,
    /// then how many more rows are not `ok`.
    pub fn warning_lines(&self) -> Vec<String> {
        let mut lines = self.warnings.clone();
        let more = self.not_ok().saturating_sub(self.warnings.len());
        if more > 0 {
            lines.push(format!(
                "{more} more rows with a status other than ok (see the status column)"
            ));
        }
        lines
    }

    /// Rows whose status is not `ok` (each has a warning, the first ones
    /// kept in [`StatusCount::warnings`]).
    pub fn not_ok(&self) -> usize {
        self.not_ok
    }

    /// Rows counted.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Records a row answered with `cautions` (none: `ok`) at `at`, and
    /// returns its status column.
    pub fn answered_with(&mut self, at: &str, cautions: &[Caution]) -> String {
        let status = status_of(cautions);
        let warning = cautions
            .first()
            .map(|c| format!("{at}: {c}; answered anyway"));
        self.answered(&status, warning);
        status
    }

    /// Records a row without an answer.
    pub fn failed(&mut self, error: &LocateError, at: &str) {
        self.rows += 1;
        *self.counts.entry(error.status().to_string()).or_default() += 1;
        self.warn(format!("{at}: {error}; no answer"));
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
}
