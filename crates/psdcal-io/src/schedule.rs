//! schedule.csv and tones.csv (docs/formats.md): which light is on when in a
//! raw recording, and each LED's modulation frequency when several are on at
//! once.
//!
//! schedule.csv: `image`, `t_start_s`, `t_stop_s` (the interval
//! `[start, stop)`, seconds from the first sample) and optionally `led`. With
//! `led`, every row names the one LED that is on (time multiplexing); without
//! it, every LED of tones.csv is on during each interval (frequency
//! multiplexing). Times are finite, `0 ≤ start < stop`; intervals may come in
//! any order but must not overlap (the error names both lines).
//!
//! tones.csv: `led` (unique) and `frequency_hz` (finite, positive).

use std::path::Path;

use crate::csv_table::CsvTable;
use crate::error::IoError;
use crate::limits::ReadLimits;

/// One interval of the schedule.
#[derive(Debug, Clone, PartialEq)]
pub struct ScheduleRow {
    /// Image identifier.
    pub image: String,
    /// The LED on (time multiplexing), or `None` (every tone at once).
    pub led: Option<String>,
    /// Start, s from the first sample.
    pub t_start_s: f64,
    /// Stop (excluded), s.
    pub t_stop_s: f64,
    /// Physical line, 1-based.
    pub line_no: usize,
}

/// A schedule: its rows sorted by start time.
#[derive(Debug, Clone, PartialEq)]
pub struct Schedule {
    /// File name, for messages.
    pub source: String,
    /// Rows by increasing start.
    pub rows: Vec<ScheduleRow>,
    /// The file has an `led` column (time multiplexing).
    pub time_multiplexed: bool,
}

impl Schedule {
    /// Reads schedule.csv.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, IoError> {
        Self::read_with(path, ReadLimits::default())
    }

    /// [`Self::read`] within `limits` (docs/formats.md, "Limits").
    pub fn read_with(path: impl AsRef<Path>, limits: ReadLimits) -> Result<Self, IoError> {
        Self::from_table(CsvTable::read_path(
            path.as_ref(),
            SCHEDULE_COLUMNS,
            limits,
        )?)
    }

    /// Parses schedule.csv text; `source` names it in messages.
    pub fn from_str(source: &str, text: &str) -> Result<Self, IoError> {
        Self::from_table(CsvTable::parse(source, text.as_bytes(), SCHEDULE_COLUMNS)?)
    }

    fn from_table(table: CsvTable) -> Result<Self, IoError> {
        table.require_rows()?;
        let image = table.column("image")?;
        let start = table.column("t_start_s")?;
        let stop = table.column("t_stop_s")?;
        let led = table.find_column("led")?;
        let mut rows = Vec::with_capacity(table.rows.len());
        for row in &table.rows {
            let t_start_s = table.number(row, &start)?;
            let t_stop_s = table.number(row, &stop)?;
            if t_start_s < 0.0 {
                return Err(IoError::Value {
                    at: table.at(row.line),
                    column: start.to_ref(),
                    message: format!("found {t_start_s}; expected a time at or after 0 s"),
                });
            }
            if t_stop_s <= t_start_s {
                return Err(IoError::Value {
                    at: table.at(row.line),
                    column: stop.to_ref(),
                    message: format!(
                        "found {t_stop_s}; expected a stop after the start {t_start_s}"
                    ),
                });
            }
            rows.push(ScheduleRow {
                image: table.identifier(row, &image, "an image identifier")?,
                led: match &led {
                    Some(col) => Some(table.identifier(row, col, "an LED identifier")?),
                    None => None,
                },
                t_start_s,
                t_stop_s,
                line_no: row.line,
            });
        }
        rows.sort_by(|a, b| a.t_start_s.total_cmp(&b.t_start_s));
        for pair in rows.windows(2) {
            if pair[1].t_start_s < pair[0].t_stop_s {
                return Err(IoError::Structure {
                    at: table.at(pair[1].line_no),
                    message: format!(
                        "the interval [{}, {}) s overlaps [{}, {}) s of line {}; expected \
                         intervals that do not overlap",
                        pair[1].t_start_s,
                        pair[1].t_stop_s,
                        pair[0].t_start_s,
                        pair[0].t_stop_s,
                        pair[0].line_no
                    ),
                });
            }
        }
        Ok(Self {
            source: table.source.clone(),
            rows,
            time_multiplexed: led.is_some(),
        })
    }
}

const SCHEDULE_COLUMNS: &str = "image, t_start_s, t_stop_s (and optionally led)";
const TONES_COLUMNS: &str = "led, frequency_hz";

/// One LED's tone.
#[derive(Debug, Clone, PartialEq)]
pub struct Tone {
    /// LED identifier.
    pub led: String,
    /// Modulation frequency, Hz.
    pub frequency_hz: f64,
    /// Physical line, 1-based.
    pub line_no: usize,
}

/// tones.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct Tones {
    /// File name, for messages.
    pub source: String,
    /// The tones, in file order.
    pub tones: Vec<Tone>,
}

impl Tones {
    /// Reads tones.csv.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, IoError> {
        Self::read_with(path, ReadLimits::default())
    }

    /// [`Self::read`] within `limits` (docs/formats.md, "Limits").
    pub fn read_with(path: impl AsRef<Path>, limits: ReadLimits) -> Result<Self, IoError> {
        Self::from_table(CsvTable::read_path(path.as_ref(), TONES_COLUMNS, limits)?)
    }

    /// Parses tones.csv text; `source` names it in messages.
    pub fn from_str(source: &str, text: &str) -> Result<Self, IoError> {
        Self::from_table(CsvTable::parse(source, text.as_bytes(), TONES_COLUMNS)?)
    }

    fn from_table(table: CsvTable) -> Result<Self, IoError> {
        table.require_rows()?;
        let led = table.column("led")?;
        let freq = table.column("frequency_hz")?;
        let mut tones: Vec<Tone> = Vec::with_capacity(table.rows.len());
        for row in &table.rows {
            let id = table.identifier(row, &led, "an LED identifier")?;
            let frequency_hz = table.number(row, &freq)?;
            if frequency_hz <= 0.0 {
                return Err(IoError::Value {
                    at: table.at(row.line),
                    column: freq.to_ref(),
                    message: format!("found {frequency_hz}; expected a positive frequency"),
                });
            }
            if let Some(first) = tones.iter().find(|t| t.led == id) {
                return Err(IoError::Structure {
                    at: table.at(row.line),
                    message: format!(
                        "LED '{}' appears twice (first on line {}); expected one tone per LED",
                        crate::limits::excerpt(&id),
                        first.line_no
                    ),
                });
            }
            tones.push(Tone {
                led: id,
                frequency_hz,
                line_no: row.line,
            });
        }
        Ok(Self {
            source: table.source.clone(),
            tones,
        })
    }
}

/// Writes schedule.csv (`image,led,t_start_s,t_stop_s`, or without `led`
/// when every row's is `None`), with a leading comment.
pub fn write_schedule(
    path: impl AsRef<Path>,
    comment: &str,
    rows: &[ScheduleRow],
) -> Result<(), IoError> {
    use crate::number_text::number_text;
    use std::io::Write;
    let with_led = rows.iter().any(|r| r.led.is_some());
    crate::atomic::write_atomic(path, |w| {
        for line in comment.lines() {
            writeln!(w, "# {line}")?;
        }
        writeln!(
            w,
            "{}",
            if with_led {
                "image,led,t_start_s,t_stop_s"
            } else {
                "image,t_start_s,t_stop_s"
            }
        )?;
        for r in rows {
            let times = format!("{},{}", number_text(r.t_start_s), number_text(r.t_stop_s));
            match (&r.led, with_led) {
                (Some(led), true) => writeln!(w, "{},{},{}", r.image, led, times)?,
                _ => writeln!(w, "{},{}", r.image, times)?,
            }
        }
        Ok(())
    })
}

/// Writes tones.csv (`led,frequency_hz`), with a leading comment.
pub fn write_tones(path: impl AsRef<Path>, comment: &str, tones: &[Tone]) -> Result<(), IoError> {
    use crate::number_text::number_text;
    use std::io::Write;
    crate::atomic::write_atomic(path, |w| {
        for line in comment.lines() {
            writeln!(w, "# {line}")?;
        }
        writeln!(w, "led,frequency_hz")?;
        for t in tones {
            writeln!(w, "{},{}", t.led, number_text(t.frequency_hz))?;
        }
        Ok(())
    })
}
