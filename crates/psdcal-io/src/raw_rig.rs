//! A rig's recording as raw.csv or raw.npy (docs/formats.md, "Raw
//! recordings"): every sensor's four channels, rows of `4 S` values in
//! rig.json's order of the sensors (`SENSOR/vx1, SENSOR/vx2, SENSOR/vy1,
//! SENSOR/vy2` each), read block by block in constant memory.
//!
//! - **raw.csv**: the columns `SENSOR/vx1` … for every sensor (found by name,
//!   any order, case ignored; other columns ignored) and optionally `t_s`.
//!   The rate is `--rate`, or `1 / (t_1 − t_0)` from the first two rows;
//!   every later step must stay within [`RATE_TOLERANCE`] of `1 / rate`
//!   (an error names the line). A field that is not a finite number is an
//!   error naming its line and column.
//! - **raw.npy**: float32 or float64, shape `(N, 4 S)`, C order; the rate is
//!   `--rate`.
//!
//! (raw.tdms is read by `sample_stream.rs`: a group per sensor.)

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

use crate::csv_table::{Col, CsvStream};
use crate::error::IoError;
use crate::location::Location;
use crate::raw::{read_npy_preamble, NpyType, RawFormat};
use crate::raw_csv::{rate_from_first_step, NO_RATE};
use crate::raw_frame::{CHANNELS, RATE_TOLERANCE};

/// The read buffer, bytes.
const READ_BUFFER_BYTES: usize = 1 << 18;

/// A rig's raw.csv or raw.npy, row by row.
pub(crate) enum RigFrames {
    /// raw.csv.
    Csv {
        stream: Box<CsvStream<BufReader<File>>>,
        cols: Vec<Col>,
        time: Option<Col>,
        rate_hz: f64,
        last_time: Option<(f64, usize)>,
        /// Rows read ahead (to find the rate), their values in order.
        pending: Vec<f64>,
    },
    /// raw.npy.
    Npy {
        source: String,
        reader: BufReader<File>,
        dtype: NpyType,
        width: usize,
        remaining: u64,
        /// Rows handed out so far.
        done: u64,
        buf: Vec<u8>,
    },
}

fn structure(at: Location, message: String) -> IoError {
    IoError::Structure { at, message }
}

impl RigFrames {
    /// Opens the rig's recording `path` (`.csv` or `.npy`) of the `sensors`
    /// in rig.json's order; returns it with its sample rate (`rate_hz`, or
    /// from `t_s`).
    pub fn open(
        path: &Path,
        sensors: &[String],
        rate_hz: Option<f64>,
    ) -> Result<(Self, f64), IoError> {
        let source = path.display().to_string();
        if let Some(rate) = rate_hz {
            if !(rate.is_finite() && rate > 0.0) {
                return Err(structure(
                    Location::file(&source),
                    format!("the sample rate {rate} Hz is not usable; expected a finite, positive --rate"),
                ));
            }
        }
        let file = File::open(path).map_err(|e| IoError::Read {
            file: source.clone(),
            source: e,
        })?;
        let reader = BufReader::with_capacity(READ_BUFFER_BYTES, file);
        match RawFormat::of_path(path) {
            Some(RawFormat::Csv) => Self::csv(&source, reader, sensors, rate_hz),
            Some(RawFormat::Npy) => {
                let rate = rate_hz.ok_or_else(|| {
                    structure(
                        Location::file(&source),
                        "a .npy recording carries no sample rate; expected --rate HZ".to_string(),
                    )
                })?;
                let mut reader = reader;
                let width = 4 * sensors.len();
                let (dtype, rows) = read_npy_preamble(&source, &mut reader, width as u64)?;
                let frames = RigFrames::Npy {
                    source,
                    reader,
                    dtype,
                    width,
                    remaining: rows,
                    done: 0,
                    buf: Vec::new(),
                };
                Ok((frames, rate))
            }
            _ => Err(structure(
                Location::file(&source),
                "unknown raw recording format; expected a file ending in .csv, .npy or .tdms"
                    .to_string(),
            )),
        }
    }

    /// raw.csv: the header's columns and the rate (from the first two
    /// rows' `t_s` without `rate_hz`; those rows are kept for the reader).
    fn csv(
        source: &str,
        reader: BufReader<File>,
        sensors: &[String],
        rate_hz: Option<f64>,
    ) -> Result<(Self, f64), IoError> {
        let expected =
            "SENSOR/vx1, SENSOR/vx2, SENSOR/vy1, SENSOR/vy2 per sensor (and optionally t_s)";
        let mut stream = CsvStream::new(source, reader, expected, None)?;
        let head = &stream.head;
        let mut cols = Vec::with_capacity(4 * sensors.len());
        for s in sensors {
            for c in CHANNELS {
                cols.push(head.column(&format!("{s}/{c}"))?);
            }
        }
        let time = head.find_column("t_s")?;
        let header_line = head.header_line;
        let mut pending = Vec::new();
        let mut last_time = None;
        let rate = match (rate_hz, &time) {
            (Some(rate), _) => rate,
            (None, None) => {
                return Err(structure(
                    Location::line(source, header_line),
                    NO_RATE.to_string(),
                ))
            }
            (None, Some(col)) => {
                let mut times = Vec::new();
                while times.len() < 2 {
                    let Some(row) = stream.next_row()? else { break };
                    times.push((stream.head.number(&row, col)?, row.line));
                    for c in &cols {
                        pending.push(stream.head.number(&row, c)?);
                    }
                }
                let (rate, last) = rate_from_first_step(&times).map_err(|(line, m)| {
                    structure(Location::line(source, line.unwrap_or(header_line)), m)
                })?;
                last_time = Some(last);
                rate
            }
        };
        let frames = RigFrames::Csv {
            stream: Box::new(stream),
            cols,
            time,
            rate_hz: rate,
            last_time,
            pending,
        };
        Ok((frames, rate))
    }

    /// Appends up to `max` rows (`4 S` values each) to `out`; returns how
    /// many (0 at the end).
    pub fn read_rows(&mut self, out: &mut Vec<f64>, max: usize) -> Result<usize, IoError> {
        match self {
            RigFrames::Csv {
                stream,
                cols,
                time,
                rate_hz,
                last_time,
                pending,
            } => {
                let mut n = 0;
                if !pending.is_empty() && max > 0 {
                    n = (pending.len() / cols.len()).min(max);
                    out.extend(pending.drain(..n * cols.len()));
                }
                while n < max {
                    let Some(row) = stream.next_row()? else { break };
                    let head = &stream.head;
                    if let Some(col) = time {
                        let t = head.number(&row, col)?;
                        if let Some((previous, previous_line)) = *last_time {
                            let expected = 1.0 / *rate_hz;
                            if ((t - previous) - expected).abs() > RATE_TOLERANCE * expected {
                                return Err(structure(
                                    head.at(row.line),
                                    format!(
                                        "t_s steps from {previous} (line {previous_line}) to {t}; \
                                         expected a step of {expected} s (a uniform sample rate \
                                         of {rate_hz} Hz)"
                                    ),
                                ));
                            }
                        }
                        *last_time = Some((t, row.line));
                    }
                    for c in cols.iter() {
                        out.push(head.number(&row, c)?);
                    }
                    n += 1;
                }
                Ok(n)
            }
            RigFrames::Npy {
                source,
                reader,
                dtype,
                width,
                remaining,
                done,
                buf,
            } => {
                let n = (max as u64).min(*remaining) as usize;
                let row_bytes = *width * dtype.bytes;
                buf.resize(n * row_bytes, 0);
                let read_error = |e: std::io::Error| IoError::Read {
                    file: source.clone(),
                    source: e,
                };
                if n == 0 {
                    let mut extra = [0u8; 1];
                    if reader.read(&mut extra).map_err(read_error)? > 0 {
                        return Err(structure(
                            Location::file(source),
                            "bytes after the rows the header announces; expected the file to \
                             end with the array"
                                .to_string(),
                        ));
                    }
                    return Ok(0);
                }
                let left = *remaining;
                reader.read_exact(buf).map_err(|e| {
                    if e.kind() == std::io::ErrorKind::UnexpectedEof {
                        structure(
                            Location::file(source),
                            format!(
                                "the file is truncated: {left} more rows of {width} values \
                                 announced; expected the whole array"
                            ),
                        )
                    } else {
                        read_error(e)
                    }
                })?;
                let first = out.len();
                for v in buf.chunks_exact(dtype.bytes) {
                    out.push(match (dtype.bytes, dtype.big_endian) {
                        (4, false) => f32::from_le_bytes([v[0], v[1], v[2], v[3]]) as f64,
                        (4, true) => f32::from_be_bytes([v[0], v[1], v[2], v[3]]) as f64,
                        (_, false) => f64::from_le_bytes(v.try_into().unwrap_or([0; 8])),
                        (_, true) => f64::from_be_bytes(v.try_into().unwrap_or([0; 8])),
                    });
                }
                if let Some(i) = out[first..].iter().position(|v| !v.is_finite()) {
                    return Err(structure(
                        Location::file(source),
                        format!(
                            "sample row {} (0-based), column {}: not a finite number; expected \
                             finite volts",
                            *done + (i / *width) as u64,
                            i % *width
                        ),
                    ));
                }
                *remaining -= n as u64;
                *done += n as u64;
                Ok(n)
            }
        }
    }
}
