//! raw.csv read frame by frame (docs/formats.md, "Raw recordings"; the
//! rules of the `t_s` column and the rate are in `raw.rs`'s documentation).
//!
//! Two paths give the same frames and the same errors. The general CSV
//! reader (`csv_table`: any quoting, comments, blank lines, every error
//! with its line and column) reads the header, the first two rows when the
//! rate comes from `t_s`, and every line the fast path leaves; the numeric
//! fast path (`csv_numeric`) reads the plain lines of numbers straight from
//! the input's buffer. The fast path takes a line only when the general
//! reader would read it to the same values without an error, and also
//! checks the `t_s` step exactly as [`CsvFrames::check_time`] does (the same
//! floating-point operations), leaving a line whose step is wrong to the
//! general reader, which reports it. Memory stays that of the input's
//! buffer, whatever the file size.

use std::io::BufRead;

use crate::csv_numeric::NumericLine;
use crate::csv_table::{Col, CsvRow, CsvStream};
use crate::error::IoError;
use crate::location::Location;
use crate::raw_frame::{Frame, CHANNELS, RATE_TOLERANCE};

/// raw.csv's columns, for messages.
pub(crate) const EXPECTED_COLUMNS: &str = "vx1, vx2, vy1, vy2 (and optionally t_s)";

/// raw.csv, row by row.
pub(crate) struct CsvFrames<R> {
    stream: CsvStream<R>,
    cols: [Col; 4],
    time: Option<Col>,
    /// The sample rate, Hz.
    pub rate_hz: f64,
    /// The plain lines' layout: the channels to slots 0–3, `t_s` to 4.
    numeric: NumericLine,
    /// The first row, read ahead to find the rate from `t_s`.
    pending: Vec<Frame>,
    /// The last time and its line.
    last_time: Option<(f64, usize)>,
    /// Rows read by the fast path.
    pub fast_rows: u64,
}

/// Whether the step from `previous` to `t` is within [`RATE_TOLERANCE`] of
/// `1 / rate_hz`.
#[inline]
fn step_within(previous: f64, t: f64, rate_hz: f64) -> bool {
    let step = t - previous;
    let expected = 1.0 / rate_hz;
    (step - expected).abs() <= RATE_TOLERANCE * expected
}

impl<R: BufRead> CsvFrames<R> {
    pub fn new(source: &str, reader: R, rate_hz: Option<f64>) -> Result<Self, IoError> {
        let stream = CsvStream::new(source, reader, EXPECTED_COLUMNS, None)?;
        let head = &stream.head;
        let cols = [
            head.column(CHANNELS[0])?,
            head.column(CHANNELS[1])?,
            head.column(CHANNELS[2])?,
            head.column(CHANNELS[3])?,
        ];
        let time = head.find_column("t_s")?;
        let header_line = head.header_line;
        let mut wanted: Vec<usize> = cols.iter().map(|c| c.index).collect();
        wanted.extend(time.as_ref().map(|c| c.index));
        let numeric = NumericLine::new(head.header.len(), &wanted);
        let mut frames = Self {
            stream,
            cols,
            time,
            rate_hz: rate_hz.unwrap_or(f64::NAN),
            numeric,
            pending: Vec::new(),
            last_time: None,
            fast_rows: 0,
        };
        let structure = |line: usize, message: String| IoError::Structure {
            at: Location::line(source, line),
            message,
        };
        match (rate_hz, frames.time.is_some()) {
            (None, false) => return Err(structure(header_line, NO_RATE.to_string())),
            (None, true) => {
                // The rate from the first step.
                let mut rows = Vec::new();
                for _ in 0..2 {
                    if let Some(row) = frames.stream.next_row()? {
                        let frame = frames.frame(&row)?;
                        rows.push((frame, frames.time_of(&row)?, row.line));
                    }
                }
                let times: Vec<(f64, usize)> = rows.iter().map(|r| (r.1, r.2)).collect();
                let (rate, last) = rate_from_first_step(&times)
                    .map_err(|(line, m)| structure(line.unwrap_or(header_line), m))?;
                frames.rate_hz = rate;
                frames.last_time = Some(last);
                // Popped from the end: the first row last.
                frames.pending = rows.iter().rev().map(|r| r.0).collect();
            }
            (Some(_), _) => {}
        }
        Ok(frames)
    }

    fn frame(&self, row: &CsvRow) -> Result<Frame, IoError> {
        let head = &self.stream.head;
        Ok([
            head.number(row, &self.cols[0])?,
            head.number(row, &self.cols[1])?,
            head.number(row, &self.cols[2])?,
            head.number(row, &self.cols[3])?,
        ])
    }

    fn time_of(&self, row: &CsvRow) -> Result<f64, IoError> {
        match &self.time {
            Some(col) => self.stream.head.number(row, col),
            None => Ok(f64::NAN),
        }
    }

    /// Checks the step from the previous time to `t` (line `line`).
    fn check_time(&mut self, t: f64, line: usize) -> Result<(), IoError> {
        if let Some((previous, previous_line)) = self.last_time {
            if !step_within(previous, t, self.rate_hz) {
                let expected = 1.0 / self.rate_hz;
                return Err(IoError::Structure {
                    at: Location::line(&self.stream.head.source, line),
                    message: format!(
                        "t_s steps from {previous} (line {previous_line}) to {t}; expected a \
                         step of {expected} s (a uniform sample rate of {} Hz)",
                        self.rate_hz
                    ),
                });
            }
        }
        self.last_time = Some((t, line));
        Ok(())
    }

    /// Appends up to `max` frames to `out`; returns how many (0 at the end).
    pub fn read(&mut self, out: &mut Vec<Frame>, max: usize) -> Result<usize, IoError> {
        let mut n = 0;
        while n < max {
            if let Some(frame) = self.pending.pop() {
                out.push(frame);
                n += 1;
                continue;
            }
            let Some(plain) = self.read_plain(out, max - n)? else {
                break;
            };
            n += plain;
            if n == max {
                break;
            }
            // A line the fast path leaves (or the end of the input).
            let Some(row) = self.stream.next_row()? else {
                break;
            };
            let frame = self.frame(&row)?;
            if self.time.is_some() {
                let t = self.time_of(&row)?;
                self.check_time(t, row.line)?;
            }
            out.push(frame);
            n += 1;
        }
        Ok(n)
    }

    /// The fast path: appends the frames of up to `max` plain lines from
    /// the input's buffer, stopping at the first other line; returns how
    /// many, or `None` at the end of the input.
    fn read_plain(&mut self, out: &mut Vec<Frame>, max: usize) -> Result<Option<usize>, IoError> {
        let lines = self.stream.lines();
        let first_line = lines.line() + 1;
        let Some(bytes) = lines.buffered()? else {
            return Ok(None);
        };
        let timed = self.time.is_some();
        let mut values = [0.0; 5];
        let mut used = 0;
        let mut n = 0;
        while n < max {
            let Some(len) = self.numeric.parse(&bytes[used..], &mut values) else {
                break;
            };
            if timed {
                let t = values[4];
                if let Some((previous, _)) = self.last_time {
                    if !step_within(previous, t, self.rate_hz) {
                        break;
                    }
                }
                self.last_time = Some((t, first_line + n));
            }
            out.push([values[0], values[1], values[2], values[3]]);
            used += len;
            n += 1;
        }
        lines.consume_lines(used, n);
        self.fast_rows += n as u64;
        Ok(Some(n))
    }
}

/// A recording without `t_s` and without `--rate`.
pub(crate) const NO_RATE: &str = "no t_s column and no --rate: expected a t_s column (seconds) \
                                  or the sample rate as --rate HZ";

/// A time `t_s` and its line.
pub(crate) type TimedLine = (f64, usize);

/// Why the sample rate cannot come from `t_s`: the line at fault (none:
/// the header's) and the message.
pub(crate) type RateFault = (Option<usize>, String);

/// The sample rate from a recording's first two times, and the second.
pub(crate) fn rate_from_first_step(times: &[TimedLine]) -> Result<(f64, TimedLine), RateFault> {
    let [(t0, _), (t1, line1)] = times else {
        return Err((
            None,
            "fewer than two rows: the sample rate cannot come from t_s; expected more rows or \
             --rate HZ"
                .to_string(),
        ));
    };
    let step = t1 - t0;
    if !(step > 0.0 && (1.0 / step).is_finite()) {
        return Err((
            Some(*line1),
            format!("t_s does not increase ({t0} then {t1}); expected uniformly increasing times"),
        ));
    }
    Ok((1.0 / step, (*t1, *line1)))
}
