//! The error type of psdcal's file formats.
//!
//! Every data error names the file, the physical line (1-based, counting
//! comments and blank lines) and, where a value is at fault, the column by
//! header name and 1-based number, then says what was expected:
//!
//! ```text
//! observations.csv:17: column 'x_mm' (3): expected a number, found 'abc'
//! calibration.json:7:16: intrinsics.f_mm must be positive, found -1
//! ```
//!
//! Messages are single lines, so a command-line tool can print one
//! `error: ...` line per failure.

use std::fmt;

use psdcal_model::ModelError;
use thiserror::Error;

use crate::location::Location;
use crate::warning::Warning;

/// A CSV column: its header name and 1-based position.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ColumnRef {
    /// Header name as written in the file (trimmed).
    pub name: String,
    /// 1-based column number.
    pub number: usize,
}

/// What makes a sample stream unreadable ([`IoError::Stream`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StreamFault {
    /// The options do not fit the recording (its format, its rate).
    Options,
    /// The stream's header lacks a needed column.
    Header,
}

impl fmt::Display for ColumnRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "column '{}' ({})", self.name, self.number)
    }
}

/// Everything that can go wrong reading or writing psdcal's files.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum IoError {
    /// The file could not be opened or read.
    #[error("{file}: cannot read the file: {source}")]
    Read {
        /// File name as given.
        file: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file could not be written.
    #[error("{file}: cannot write the file: {source}")]
    Write {
        /// File name as given.
        file: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file is not UTF-8 text (binary data or another encoding).
    #[error("{at}: {message}")]
    Encoding {
        /// Where the first offending byte is.
        at: Location,
        /// What was found and what was expected.
        message: String,
    },
    /// The file's structure is wrong: empty, no header, wrong delimiter,
    /// missing column, wrong number of fields, unterminated quote.
    #[error("{at}: {message}")]
    Structure {
        /// Where.
        at: Location,
        /// What was found and what was expected.
        message: String,
    },
    /// The file is larger than the size limit (docs/formats.md, "Limits").
    #[error("{at}: {message}")]
    TooLarge {
        /// The file.
        at: Location,
        /// The limit and how to raise it.
        message: String,
    },
    /// An output would replace a file in its folder that psdcal did not
    /// write there (or that changed since; docs/formats.md, "Output
    /// folders").
    #[error("{file}: {message}")]
    NotOurs {
        /// The file that would be replaced.
        file: String,
        /// Why it is kept.
        message: String,
    },
    /// An output would replace an input of the same run (the same file,
    /// also through links), or two outputs are the same file.
    #[error("{file}: {message}")]
    OutputIsInput {
        /// The output as given.
        file: String,
        /// Which input it is, and what to do.
        message: String,
    },
    /// A value in a CSV column is unusable (not a number, not finite, empty).
    #[error("{at}: {column}: {message}")]
    Value {
        /// Where.
        at: Location,
        /// Which column.
        column: ColumnRef,
        /// What was found and what was expected.
        message: String,
    },
    /// An observation names an LED the template does not have.
    #[error("{at}: LED '{led}' is not in the template {template}; expected one of its LED ids")]
    UnknownLed {
        /// Where the observation is.
        at: Location,
        /// The unknown identifier.
        led: String,
        /// The template file.
        template: String,
    },
    /// The same key appears twice (an LED in the template, an (image, LED)
    /// pair in the observations).
    #[error("{at}: {what} appears twice (first on line {first_line})")]
    Duplicate {
        /// The second occurrence.
        at: Location,
        /// Line of the first occurrence.
        first_line: usize,
        /// What is duplicated, e.g. `LED '5'`.
        what: String,
    },
    /// The data are well-formed but unusable as a whole (too few LEDs, no
    /// usable image, inconsistent calibration fields).
    #[error("{at}: {message}")]
    Invalid {
        /// Where.
        at: Location,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A sample stream that cannot be read as asked (the text says why).
    #[error("{message}")]
    Stream {
        /// Whose fault: the options or the stream's header.
        fault: StreamFault,
        /// What is wrong and what to do.
        message: String,
    },
    /// An amplitude row cannot give an impact point (docs/model.md §1).
    #[error("{at}: {source}")]
    Amplitudes {
        /// The row.
        at: Location,
        /// The model's reason.
        source: ModelError,
    },
    /// calibration.json could not be parsed or holds an invalid value; JSON
    /// errors come with line and character column.
    #[error("{file}:{line}:{column}: {message}")]
    Json {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based character column.
        column: usize,
        /// What was found and what was expected.
        message: String,
    },
    /// calibration.json was written by a newer psdcal, with a format version
    /// this one cannot read.
    #[error(
        "{file}:{line}:{column}: format version {found} was written by a newer psdcal; this \
         psdcal reads versions up to {supported}"
    )]
    NewerVersion {
        /// File name.
        file: String,
        /// 1-based line of the version.
        line: usize,
        /// 1-based character column just after the version.
        column: usize,
        /// The file's version.
        found: u64,
        /// The newest version this psdcal reads.
        supported: u32,
    },
    /// A JSON field (named by its path, e.g. `sensors[1].t_mm`) is missing or
    /// holds an invalid value: the rig file's errors.
    #[error("{file}: field '{field}': {message}")]
    Field {
        /// File name.
        file: String,
        /// Path of the field, e.g. `sensors[1].world_from_sensor.t_mm`.
        field: String,
        /// What was found and what was expected.
        message: String,
    },
    /// A warning raised to an error by strict validation.
    #[error("{} (strict validation makes this warning an error)", .warning.problem())]
    Strict {
        /// The warning.
        warning: Warning,
    },
}

impl IoError {
    /// The file the error is about.
    pub fn file(&self) -> Option<&str> {
        match self {
            IoError::Read { file, .. }
            | IoError::Write { file, .. }
            | IoError::Json { file, .. }
            | IoError::NewerVersion { file, .. }
            | IoError::Field { file, .. }
            | IoError::NotOurs { file, .. }
            | IoError::OutputIsInput { file, .. } => Some(file),
            IoError::Encoding { at, .. }
            | IoError::Structure { at, .. }
            | IoError::TooLarge { at, .. }
            | IoError::Value { at, .. }
            | IoError::UnknownLed { at, .. }
            | IoError::Duplicate { at, .. }
            | IoError::Invalid { at, .. }
            | IoError::Amplitudes { at, .. } => Some(&at.file),
            IoError::Strict { warning } => Some(warning.file()),
            IoError::Stream { .. } => None,
        }
    }

    /// The 1-based physical line the error is on, if it is on one.
    pub fn line(&self) -> Option<usize> {
        match self {
            IoError::Read { .. }
            | IoError::Write { .. }
            | IoError::Field { .. }
            | IoError::OutputIsInput { .. }
            | IoError::NotOurs { .. }
            | IoError::Stream { .. } => None,
            IoError::Json { line, .. } | IoError::NewerVersion { line, .. } => Some(*line),
            IoError::Encoding { at, .. }
            | IoError::Structure { at, .. }
            | IoError::TooLarge { at, .. }
            | IoError::Value { at, .. }
            | IoError::UnknownLed { at, .. }
            | IoError::Duplicate { at, .. }
            | IoError::Invalid { at, .. }
            | IoError::Amplitudes { at, .. } => at.line,
            IoError::Strict { warning } => warning.line(),
        }
    }
}

/// A JSON syntax or type error of `source` with its line and column, the
/// message without serde's own position and at most 160 characters long.
pub(crate) fn json_error(source: &str, e: &serde_json::Error) -> IoError {
    let full = e.to_string();
    let suffix = format!(" at line {} column {}", e.line(), e.column());
    let message = full.strip_suffix(&suffix).unwrap_or(&full);
    let mut shown: String = message.chars().take(160).collect();
    if message.chars().nth(160).is_some() {
        shown.push('…');
    }
    IoError::Json {
        file: source.to_string(),
        line: e.line().max(1),
        column: e.column(),
        message: shown,
    }
}

/// A raw field as shown in messages: quoted, control characters escaped,
/// long text shortened.
pub(crate) fn quoted(raw: &str) -> String {
    const MAX_CHARS: usize = 40;
    let mut shown: String = raw.chars().take(MAX_CHARS).collect();
    if raw.chars().count() > MAX_CHARS {
        shown.push('…');
    }
    format!("'{}'", shown.escape_debug())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_error_reads_like_the_spec_example() {
        let e = IoError::Value {
            at: Location::line("observations.csv", 17),
            column: ColumnRef {
                name: "x_mm".into(),
                number: 3,
            },
            message: "expected a number, found 'abc'".into(),
        };
        assert_eq!(
            e.to_string(),
            "observations.csv:17: column 'x_mm' (3): expected a number, found 'abc'"
        );
        assert_eq!(e.line(), Some(17));
        assert_eq!(e.file(), Some("observations.csv"));
    }

    #[test]
    fn quoted_escapes_and_shortens() {
        assert_eq!(quoted("a\tb"), "'a\\tb'");
        let long = "x".repeat(50);
        assert_eq!(quoted(&long), format!("'{}…'", "x".repeat(40)));
    }
}
