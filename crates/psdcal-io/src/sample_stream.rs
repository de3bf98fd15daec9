//! A stream of samples (what `psdcal track` reads): rows of `4 S` values (S sensors, each
//! `vx1, vx2, vy1, vy2`, volts) from a text stream as they arrive, or from a
//! recording file (docs/formats.md, "Raw recordings").
//!
//! Text stream (standard input): blank lines and `#` comments are skipped;
//! a first line naming the columns sets their order (one sensor: `vx1`,
//! `vx2`, `vy1`, `vy2`; a rig: `SENSOR/vx1` … for every sensor of
//! rig.json; extra columns ignored), otherwise the fields are the sensors
//! in rig.json's order, four each. A line that is not the needed finite
//! numbers (or not UTF-8) is [`Sample::Malformed`]; a line longer than
//! [`MAX_LINE_BYTES`] (1 MiB) is [`Sample::TooLong`], skipped without being
//! held in memory (at most 1 MiB of it is), and reading goes on.
//!
//! Recording file: one sensor, raw.csv, raw.npy or raw.tdms
//! ([`RawReader`]); a rig, raw.csv with the columns `SENSOR/vx1` … and
//! optionally `t_s`, raw.npy of `4 S` columns in rig.json's order
//! (`raw_rig.rs`), or raw.tdms with the channels `SENSOR/vx1` … (a group per
//! sensor, named by its id) or the channels named, four per sensor in
//! rig.json's order.

use std::io::{BufRead, Read};
use std::path::Path;

use crate::error::{IoError, StreamFault};
use crate::limits::MAX_LINE_BYTES;
use crate::raw::{RawFormat, RawReader};
use crate::raw_rig::RigFrames;
use crate::tdms::{TdmsReader, TDMS_DEFAULT_CHANNELS};

type Result<T> = std::result::Result<T, IoError>;

/// A stream that cannot be read as asked.
fn fault(fault: StreamFault, message: String) -> IoError {
    IoError::Stream { fault, message }
}

/// One input row.
#[derive(Debug, Clone, PartialEq)]
pub enum Sample {
    /// The `4 S` values.
    Values(Vec<f64>),
    /// A line that is not a sample.
    Malformed,
    /// A line longer than [`MAX_LINE_BYTES`], skipped.
    TooLong,
}

/// Skips the input up to and including the next newline (or to its end),
/// holding no more of it than the reader's buffer.
fn skip_line(input: &mut impl BufRead) -> std::io::Result<()> {
    loop {
        let buffer = input.fill_buf()?;
        if buffer.is_empty() {
            return Ok(());
        }
        match buffer.iter().position(|&b| b == b'\n') {
            Some(end) => {
                input.consume(end + 1);
                return Ok(());
            }
            None => {
                let n = buffer.len();
                input.consume(n);
            }
        }
    }
}

/// Rows read from a file at a time.
const BLOCK: usize = 4096;

/// Where the samples come from.
enum Source<R> {
    /// A text stream.
    Lines {
        input: R,
        sensors: Vec<String>,
        columns: Option<Vec<usize>>,
        first_line: bool,
        line: Vec<u8>,
    },
    /// One sensor's recording file.
    Raw {
        reader: Box<RawReader>,
        buffer: std::collections::VecDeque<[f64; 4]>,
    },
    /// A rig's raw.csv, raw.npy or raw.tdms.
    Rig {
        reader: Box<dyn RigRows>,
        width: usize,
        buffer: Vec<f64>,
        next: usize,
    },
}

/// A rig's recording read in blocks of rows (`4 S` values each).
trait RigRows {
    /// Appends up to `max` rows to `out`; returns how many (0 at the end).
    fn read_rows(&mut self, out: &mut Vec<f64>, max: usize) -> Result<usize>;
}

impl RigRows for RigFrames {
    fn read_rows(&mut self, out: &mut Vec<f64>, max: usize) -> Result<usize> {
        RigFrames::read_rows(self, out, max)
    }
}

impl RigRows for TdmsReader {
    fn read_rows(&mut self, out: &mut Vec<f64>, max: usize) -> Result<usize> {
        TdmsReader::read_rows(self, out, max)
    }
}

impl<R: BufRead> Source<R> {
    /// A text stream of the `sensors` (an empty id: the one sensor).
    fn lines(input: R, sensors: Vec<String>) -> Self {
        Source::Lines {
            input,
            sensors,
            columns: None,
            first_line: true,
            line: Vec::new(),
        }
    }

    /// A recording file of the `sensors`, its sample rate (`rate_hz` or the
    /// file's own).
    fn file(
        path: &Path,
        sensors: &[String],
        channels: &[String],
        rate_hz: Option<f64>,
    ) -> Result<(Self, f64)> {
        if sensors.len() == 1 && sensors[0].is_empty() {
            let reader = RawReader::open_channels(path, rate_hz, channels)?;
            let rate = reader.sample_rate_hz();
            let buffer = Default::default();
            let reader = Box::new(reader);
            return Ok((Source::Raw { reader, buffer }, rate));
        }
        let specs: Vec<String> = if channels.is_empty() {
            sensors
                .iter()
                .flat_map(|s| {
                    TDMS_DEFAULT_CHANNELS
                        .iter()
                        .map(move |c| format!("{s}/{c}"))
                })
                .collect()
        } else {
            channels.to_vec()
        };
        let format = RawFormat::of_path(path);
        if matches!(format, Some(RawFormat::Csv | RawFormat::Npy)) && channels.is_empty() {
            let (reader, rate) = RigFrames::open(path, sensors, rate_hz)?;
            let source = Source::Rig {
                reader: Box::new(reader),
                width: 4 * sensors.len(),
                buffer: Vec::new(),
                next: 0,
            };
            return Ok((source, rate));
        }
        if format != Some(RawFormat::Tdms) || specs.len() != 4 * sensors.len() {
            return Err(fault(
                StreamFault::Options,
                format!(
                    "{}: a rig's recording is raw.csv (SENSOR/vx1 … columns), raw.npy or raw.tdms \
                 (four channels per sensor; {} named, {} sensors, channels named only for \
                 .tdms); expected one of these, or the rows on standard input",
                    path.display(),
                    specs.len(),
                    sensors.len()
                ),
            ));
        }
        let reader = TdmsReader::open(path, &specs, specs.len())?;
        let increment = reader.increment_s(crate::raw_frame::RATE_TOLERANCE)?;
        let rate = match (rate_hz, increment) {
            (Some(r), _) => r,
            (None, Some(dt)) => 1.0 / dt,
            (None, None) => {
                return Err(fault(
                    StreamFault::Options,
                    format!(
                        "{}: the channels carry no wf_increment; give the sample rate as --rate HZ",
                        path.display()
                    ),
                ))
            }
        };
        let source = Source::Rig {
            reader: Box::new(reader),
            width: specs.len(),
            buffer: Vec::new(),
            next: 0,
        };
        Ok((source, rate))
    }

    /// The next row; `None` at the end of the input.
    fn next(&mut self) -> Result<Option<Sample>> {
        match self {
            Source::Raw { reader, buffer } => {
                if buffer.is_empty() {
                    let mut block = Vec::with_capacity(BLOCK);
                    reader.read_frames(&mut block, BLOCK)?;
                    buffer.extend(block);
                }
                Ok(buffer.pop_front().map(|f| Sample::Values(f.to_vec())))
            }
            Source::Rig {
                reader,
                width,
                buffer,
                next,
            } => {
                if *next >= buffer.len() {
                    buffer.clear();
                    *next = 0;
                    if reader.read_rows(buffer, BLOCK)? == 0 {
                        return Ok(None);
                    }
                }
                let row = buffer[*next..*next + *width].to_vec();
                *next += *width;
                Ok(Some(Sample::Values(row)))
            }
            Source::Lines {
                input,
                sensors,
                columns,
                first_line,
                line,
            } => loop {
                line.clear();
                let read = (&mut *input)
                    .take(MAX_LINE_BYTES as u64 + 1)
                    .read_until(b'\n', line)
                    .map_err(|source| IoError::Read {
                        file: "standard input".to_string(),
                        source,
                    })?;
                if read == 0 {
                    return Ok(None);
                }
                if line.len() > MAX_LINE_BYTES && line.last() != Some(&b'\n') {
                    skip_line(input).map_err(|source| IoError::Read {
                        file: "standard input".to_string(),
                        source,
                    })?;
                    line.clear();
                    line.shrink_to(64 << 10);
                    return Ok(Some(Sample::TooLong));
                }
                let Ok(text) = std::str::from_utf8(line) else {
                    return Ok(Some(Sample::Malformed));
                };
                let text = text.trim();
                if text.is_empty() || text.starts_with('#') {
                    continue;
                }
                let fields: Vec<&str> = text.split(',').map(str::trim).collect();
                let is_header = fields.iter().any(|f| {
                    let name = f.rsplit('/').next().unwrap_or(f);
                    name.eq_ignore_ascii_case("vx1")
                });
                if *first_line && is_header {
                    *first_line = false;
                    *columns = Some(header_columns(&fields, sensors).ok_or_else(|| {
                        fault(
                            StreamFault::Header,
                            format!(
                                "standard input: the header '{}' lacks one of {}",
                                text.chars().take(60).collect::<String>(),
                                needed(sensors)
                            ),
                        )
                    })?);
                    continue;
                }
                *first_line = false;
                let default: Vec<usize> = (0..4 * sensors.len()).collect();
                let cols = columns.as_deref().unwrap_or(&default);
                return Ok(Some(match sample(&fields, cols) {
                    Some(v) => Sample::Values(v),
                    None => Sample::Malformed,
                }));
            },
        }
    }
}

/// A stream of samples: a text stream or a recording file (module
/// documentation).
pub struct SampleSource<R>(Source<R>);

impl<R: BufRead> SampleSource<R> {
    /// A text stream of the `sensors` (an empty id: the one sensor).
    pub fn lines(input: R, sensors: Vec<String>) -> Self {
        Self(Source::lines(input, sensors))
    }

    /// A recording file of the `sensors` (four `channels` per sensor of a
    /// .tdms file, or empty for the default), and its sample rate
    /// (`rate_hz` or the file's own).
    pub fn file(
        path: &Path,
        sensors: &[String],
        channels: &[String],
        rate_hz: Option<f64>,
    ) -> Result<(Self, f64)> {
        Source::file(path, sensors, channels, rate_hz).map(|(s, rate)| (Self(s), rate))
    }

    /// The next row; `None` at the end of the input.
    pub fn next_sample(&mut self) -> Result<Option<Sample>> {
        self.0.next()
    }
}

/// The column names a header must hold.
fn needed(sensors: &[String]) -> String {
    let names: Vec<String> = sensors
        .iter()
        .flat_map(|s| {
            TDMS_DEFAULT_CHANNELS.iter().map(move |c| {
                if s.is_empty() {
                    c.to_string()
                } else {
                    format!("{s}/{c}")
                }
            })
        })
        .collect();
    let text = names.join(", ");
    text.chars().take(120).collect()
}

/// The positions of every sensor's `vx1, vx2, vy1, vy2` in a header.
fn header_columns(fields: &[&str], sensors: &[String]) -> Option<Vec<usize>> {
    let mut out = Vec::with_capacity(4 * sensors.len());
    for s in sensors {
        for c in TDMS_DEFAULT_CHANNELS {
            let name = if s.is_empty() {
                c.to_string()
            } else {
                format!("{s}/{c}")
            };
            out.push(fields.iter().position(|f| f.eq_ignore_ascii_case(&name))?);
        }
    }
    Some(out)
}

/// Finite numbers at `columns`.
fn sample(fields: &[&str], columns: &[usize]) -> Option<Vec<f64>> {
    columns
        .iter()
        .map(|&c| fields.get(c)?.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect()
}
