//! Raw recordings (docs/formats.md, "Raw recordings"): the four electrode
//! channels as a data-acquisition card sampled them, read as a stream of
//! frames `[vx1, vx2, vy1, vy2]` (volts) in constant memory, whatever the
//! file size.
//!
//! - **raw.csv**: columns `vx1`, `vx2`, `vy1`, `vy2` (found by name) and
//!   optionally `t_s`. The sample rate is `--rate` or, without it,
//!   `1 / (t_1 − t_0)` from the first two rows; every step `t_n − t_{n−1}` must
//!   then stay within [`RATE_TOLERANCE`] of `1/rate` (a gap, a repeated or a
//!   backward time is an error naming the line). With both, they must agree
//!   to the same tolerance. Write `t_s` with enough digits (or give the
//!   rate): the rate comes from the first step.
//! - **raw.npy**: a NumPy array (format versions 1–3), dtype `float32` or
//!   `float64` (`<f4`, `<f8`, `>f4`, `>f8`), shape `(N, 4)`, C order; the rate
//!   is `--rate`. A wrong dtype, shape or order, a truncated array and bytes
//!   after it are errors naming the file (and the sample row).
//!
//! - **raw.tdms**: NI TDMS (`tdms.rs`): the group with channels `vx1`,
//!   `vx2`, `vy1`, `vy2`, else the first four channels, or four named
//!   channels; the rate is `1 / wf_increment` or `--rate` (with both, they
//!   must agree to [`RATE_TOLERANCE`]).
//!
//! Every sample must be finite. Row numbers in `.npy` messages are 0-based
//! sample indices; CSV messages give the physical line.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use crate::error::IoError;
use crate::limits::excerpt;
use crate::location::Location;
use crate::raw_csv::CsvFrames;
use crate::raw_frame::{Frame, CHANNELS, RATE_TOLERANCE};
use crate::tdms::TdmsReader;

/// A header excerpt for a one-line message (control characters shown as `?`).
fn shown(text: &str) -> String {
    excerpt(text)
        .chars()
        .map(|c| if c.is_control() { '?' } else { c })
        .collect()
}

/// The read buffer of a recording opened by path, bytes: large blocks, so
/// that raw.csv's fast path rarely meets a line cut by the buffer's end.
const READ_BUFFER_BYTES: usize = 1 << 18;

/// The layout of a raw recording, from its file name's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[non_exhaustive]
pub enum RawFormat {
    /// raw.csv.
    Csv,
    /// raw.npy.
    Npy,
    /// raw.tdms.
    Tdms,
}

impl RawFormat {
    /// The format of `path` by its extension (`.csv`, `.npy`; case ignored).
    pub fn of_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "csv" => Some(Self::Csv),
            "npy" => Some(Self::Npy),
            "tdms" => Some(Self::Tdms),
            _ => None,
        }
    }
}

/// A raw recording read frame by frame.
pub struct RawReader {
    source: String,
    sample_rate_hz: f64,
    inner: Inner,
    /// Frames handed out so far.
    frames: u64,
}

enum Inner {
    Csv(Box<CsvFrames<Box<dyn BufRead>>>),
    Npy(NpyFrames<Box<dyn Read>>),
    Tdms(Box<TdmsReader>, Vec<f64>),
}

impl std::fmt::Debug for RawReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RawReader")
            .field("source", &self.source)
            .field("sample_rate_hz", &self.sample_rate_hz)
            .field("frames", &self.frames)
            .finish()
    }
}

impl RawReader {
    /// Opens `path` (its format by extension) with the sample rate
    /// `rate_hz` when given.
    pub fn open(path: &Path, rate_hz: Option<f64>) -> Result<Self, IoError> {
        Self::open_channels(path, rate_hz, &[])
    }

    /// Opens `path` like [`open`](Self::open); a .tdms file's four
    /// `channels` (`group/channel`, a unique channel name, or a TDMS path)
    /// in the order vx1, vx2, vy1, vy2, or none for the default
    /// ([`TdmsReader::from_reader`]). Channels given for another format are
    /// an error.
    pub fn open_channels(
        path: &Path,
        rate_hz: Option<f64>,
        channels: &[String],
    ) -> Result<Self, IoError> {
        let source = path.display().to_string();
        let format = RawFormat::of_path(path).ok_or_else(|| IoError::Structure {
            at: Location::file(&source),
            message: "unknown raw recording format; expected a file ending in .csv, .npy or .tdms"
                .to_string(),
        })?;
        if format != RawFormat::Tdms && !channels.is_empty() {
            return Err(IoError::Structure {
                at: Location::file(&source),
                message: "channels are named only for a .tdms recording; expected vx1, vx2, \
                          vy1, vy2 columns"
                    .to_string(),
            });
        }
        if format == RawFormat::Tdms {
            check_rate(&source, rate_hz)?;
            let tdms = TdmsReader::open(path, channels, 4)?;
            return Self::from_tdms(tdms, channels, rate_hz);
        }
        let file = File::open(path).map_err(|e| IoError::Read {
            file: source.clone(),
            source: e,
        })?;
        Self::from_reader(
            &source,
            format,
            BufReader::with_capacity(READ_BUFFER_BYTES, file),
            rate_hz,
        )
    }

    /// Reads a recording of `format` from `reader`; `source` names it in
    /// messages.
    pub fn from_reader(
        source: &str,
        format: RawFormat,
        reader: impl BufRead + 'static,
        rate_hz: Option<f64>,
    ) -> Result<Self, IoError> {
        check_rate(source, rate_hz)?;
        let (inner, sample_rate_hz) = match format {
            RawFormat::Csv => {
                let csv = CsvFrames::new(source, Box::new(reader) as Box<dyn BufRead>, rate_hz)?;
                let rate = csv.rate_hz;
                (Inner::Csv(Box::new(csv)), rate)
            }
            RawFormat::Npy => {
                let rate = rate_hz.ok_or_else(|| IoError::Structure {
                    at: Location::file(source),
                    message: "a .npy recording carries no sample rate; expected --rate HZ"
                        .to_string(),
                })?;
                let npy = NpyFrames::new(source, Box::new(reader) as Box<dyn Read>)?;
                (Inner::Npy(npy), rate)
            }
            RawFormat::Tdms => {
                return Err(IoError::Structure {
                    at: Location::file(source),
                    message: "a .tdms recording needs a seekable file; expected \
                              RawReader::open or RawReader::from_tdms"
                        .to_string(),
                })
            }
        };
        Ok(Self {
            source: source.to_string(),
            sample_rate_hz,
            inner,
            frames: 0,
        })
    }

    /// A TDMS recording of four selected channels; the rate from the
    /// channels' `wf_increment` or `rate_hz` (with both, they must agree to
    /// [`RATE_TOLERANCE`]).
    pub fn from_tdms(
        tdms: TdmsReader,
        channels: &[String],
        rate_hz: Option<f64>,
    ) -> Result<Self, IoError> {
        let source = tdms.source().to_string();
        let bad = |message: String| IoError::Structure {
            at: Location::file(&source),
            message,
        };
        let names = tdms.channel_names();
        if names.len() != 4 {
            return Err(bad(format!(
                "{} channels named ({}); expected four: vx1, vx2, vy1, vy2 in that order",
                names.len(),
                excerpt(&channels.join(", "))
            )));
        }
        let increment = tdms.increment_s(RATE_TOLERANCE)?;
        let rate = match (rate_hz, increment) {
            (Some(rate), Some(dt)) if (rate * dt - 1.0).abs() > RATE_TOLERANCE => {
                return Err(bad(format!(
                    "--rate {rate} Hz disagrees with the channels' wf_increment {dt} s ({} Hz); \
                     expected the same sample rate (or no --rate)",
                    1.0 / dt
                )))
            }
            (Some(rate), _) => rate,
            (None, Some(dt)) => 1.0 / dt,
            (None, None) => {
                return Err(bad(format!(
                    "the channels {} carry no wf_increment property; expected the sample rate as \
                     --rate HZ",
                    names.join(", ")
                )))
            }
        };
        check_rate(&source, Some(rate))?;
        Ok(Self {
            source,
            sample_rate_hz: rate,
            inner: Inner::Tdms(Box::new(tdms), Vec::new()),
            frames: 0,
        })
    }

    /// The file, as named in messages.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The sample rate, Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    /// Frames handed out so far.
    pub fn frames_read(&self) -> u64 {
        self.frames
    }

    /// Rows of a raw.csv read by the numeric fast path (plain lines of
    /// numbers read straight from the buffer); the other rows went through
    /// the general CSV reader. 0 for the other formats.
    pub fn fast_rows(&self) -> u64 {
        match &self.inner {
            Inner::Csv(csv) => csv.fast_rows,
            _ => 0,
        }
    }

    /// Appends up to `max` frames to `out`; returns how many (0 at the end).
    pub fn read_frames(&mut self, out: &mut Vec<Frame>, max: usize) -> Result<usize, IoError> {
        let n = match &mut self.inner {
            Inner::Csv(csv) => csv.read(out, max)?,
            Inner::Npy(npy) => npy.read(out, max)?,
            Inner::Tdms(tdms, values) => {
                values.clear();
                let n = tdms.read_rows(values, max)?;
                out.extend(values.chunks_exact(4).map(|v| [v[0], v[1], v[2], v[3]]));
                n
            }
        };
        self.frames += n as u64;
        Ok(n)
    }
}

/// Refuses an unusable `--rate`.
fn check_rate(source: &str, rate_hz: Option<f64>) -> Result<(), IoError> {
    match rate_hz {
        Some(rate) if !(rate.is_finite() && rate > 0.0) => Err(IoError::Structure {
            at: Location::file(source),
            message: format!(
                "the sample rate {rate} Hz is not usable; expected a finite, positive --rate"
            ),
        }),
        _ => Ok(()),
    }
}

/// The element type of a .npy array.
#[derive(Debug, Clone, Copy)]
pub(crate) struct NpyType {
    pub(crate) bytes: usize,
    pub(crate) big_endian: bool,
}

/// raw.npy, row by row.
struct NpyFrames<R> {
    source: String,
    reader: R,
    dtype: NpyType,
    rows: u64,
    next_row: u64,
    buf: Vec<u8>,
}

impl<R: Read> NpyFrames<R> {
    fn new(source: &str, mut reader: R) -> Result<Self, IoError> {
        let (dtype, rows) = read_npy_preamble(source, &mut reader, 4)?;
        Ok(Self {
            source: source.to_string(),
            reader,
            dtype,
            rows,
            next_row: 0,
            buf: Vec::new(),
        })
    }

    fn read(&mut self, out: &mut Vec<Frame>, max: usize) -> Result<usize, IoError> {
        let remaining = self.rows - self.next_row;
        let n = (max as u64).min(remaining) as usize;
        if n == 0 {
            if remaining == 0 {
                // Bytes after the array?
                let mut extra = [0u8; 1];
                let more = self.reader.read(&mut extra).map_err(|e| IoError::Read {
                    file: self.source.clone(),
                    source: e,
                })?;
                if more > 0 {
                    return Err(IoError::Structure {
                        at: Location::file(&self.source),
                        message: format!(
                            "bytes after the {} rows the header announces; expected the file \
                             to end with the array",
                            self.rows
                        ),
                    });
                }
            }
            return Ok(0);
        }
        let row_bytes = 4 * self.dtype.bytes;
        self.buf.resize(n * row_bytes, 0);
        let got = read_up_to(&mut self.reader, &mut self.buf).map_err(|e| IoError::Read {
            file: self.source.clone(),
            source: e,
        })?;
        if got < self.buf.len() {
            let row = self.next_row + (got / row_bytes) as u64;
            return Err(IoError::Structure {
                at: Location::file(&self.source),
                message: format!(
                    "the file is truncated at sample row {row} (0-based); the header announces \
                     {} rows of 4 values",
                    self.rows
                ),
            });
        }
        let first = out.len();
        out.reserve(n);
        // One decoding loop per dtype (the dtype checked once per chunk).
        match (self.dtype.bytes, self.dtype.big_endian) {
            (4, false) => decode_rows::<4>(&self.buf, out, |b| f32::from_le_bytes(b) as f64),
            (4, true) => decode_rows::<4>(&self.buf, out, |b| f32::from_be_bytes(b) as f64),
            (8, false) => decode_rows::<8>(&self.buf, out, f64::from_le_bytes),
            _ => decode_rows::<8>(&self.buf, out, f64::from_be_bytes),
        }
        let bad = out[first..]
            .iter()
            .position(|frame| !frame.iter().fold(true, |ok, v| ok & v.is_finite()));
        if let Some(i) = bad {
            let c = out[first + i]
                .iter()
                .position(|v| !v.is_finite())
                .unwrap_or(0);
            out.truncate(first);
            return Err(IoError::Structure {
                at: Location::file(&self.source),
                message: format!(
                    "sample row {} (0-based), channel {}: not a finite number; expected \
                     finite volts",
                    self.next_row + i as u64,
                    CHANNELS[c]
                ),
            });
        }
        self.next_row += n as u64;
        Ok(n)
    }
}

/// Appends the frames of `bytes` (rows of four `B`-byte values) decoded by
/// `value`.
fn decode_rows<const B: usize>(bytes: &[u8], out: &mut Vec<Frame>, value: impl Fn([u8; B]) -> f64) {
    out.extend(bytes.chunks_exact(4 * B).map(|row| {
        let at = |c: usize| {
            let mut b = [0u8; B];
            b.copy_from_slice(&row[c * B..(c + 1) * B]);
            value(b)
        };
        [at(0), at(1), at(2), at(3)]
    }));
}

/// Reads a .npy file's magic and header from `reader` (left at the
/// array's first byte): the dtype and the row count of an array of
/// `columns` columns.
pub(crate) fn read_npy_preamble(
    source: &str,
    reader: &mut impl Read,
    columns: u64,
) -> Result<(NpyType, u64), IoError> {
    let bad = |message: String| IoError::Structure {
        at: Location::file(source),
        message,
    };
    let read_err = |e: std::io::Error| {
        if e.kind() == std::io::ErrorKind::UnexpectedEof {
            bad("the file ends inside the .npy header; expected a whole NumPy file".to_string())
        } else {
            IoError::Read {
                file: source.to_string(),
                source: e,
            }
        }
    };
    let mut magic = [0u8; 8];
    read_full(reader, &mut magic).map_err(read_err)?;
    if &magic[..6] != b"\x93NUMPY" {
        return Err(bad(
            "not a NumPy .npy file (no \\x93NUMPY magic); expected an array saved with numpy.save"
                .to_string(),
        ));
    }
    let header_len = match magic[6] {
        1 => {
            let mut len = [0u8; 2];
            read_full(reader, &mut len).map_err(read_err)?;
            u16::from_le_bytes(len) as usize
        }
        2 | 3 => {
            let mut len = [0u8; 4];
            read_full(reader, &mut len).map_err(read_err)?;
            u32::from_le_bytes(len) as usize
        }
        v => {
            return Err(bad(format!(
                "NumPy format version {v} is not supported; expected version 1, 2 or 3"
            )))
        }
    };
    if header_len > 1 << 16 {
        return Err(bad(format!(
            "a .npy header of {header_len} bytes; expected at most 65536"
        )));
    }
    let mut header = vec![0u8; header_len];
    read_full(reader, &mut header).map_err(read_err)?;
    let header = String::from_utf8_lossy(&header).to_string();
    parse_npy_header(&header, columns).map_err(bad)
}

/// Reads exactly `buf.len()` bytes; a short file is `UnexpectedEof`.
fn read_full(reader: &mut impl Read, buf: &mut [u8]) -> std::io::Result<()> {
    reader.read_exact(buf)
}

/// Reads until `buf` is full or the input ends; returns the bytes read.
fn read_up_to(reader: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match reader.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// The dtype and the row count of a .npy header dictionary of `columns`
/// columns, e.g. `{'descr': '<f8', 'fortran_order': False, 'shape': (1000, 4), }`.
pub(crate) fn parse_npy_header(header: &str, columns: u64) -> Result<(NpyType, u64), String> {
    let text = header.trim();
    let value = |key: &str| -> Result<&str, String> {
        let at = text
            .find(&format!("'{key}'"))
            .ok_or_else(|| format!("the .npy header has no '{key}'; expected a NumPy header"))?;
        let rest = text[at + key.len() + 2..].trim_start();
        let rest = rest
            .strip_prefix(':')
            .ok_or_else(|| format!("the .npy header's '{key}' has no value"))?;
        Ok(rest.trim_start())
    };
    let descr = value("descr")?;
    let descr = descr
        .strip_prefix('\'')
        .and_then(|d| d.split('\'').next())
        .ok_or_else(|| "the .npy header's 'descr' is not a string".to_string())?;
    let dtype = match descr {
        "<f8" => NpyType {
            bytes: 8,
            big_endian: false,
        },
        ">f8" => NpyType {
            bytes: 8,
            big_endian: true,
        },
        "<f4" => NpyType {
            bytes: 4,
            big_endian: false,
        },
        ">f4" => NpyType {
            bytes: 4,
            big_endian: true,
        },
        other => {
            return Err(format!(
                "dtype '{}' is not supported; expected float32 or float64 (save with \
                 array.astype(numpy.float64))",
                shown(other)
            ))
        }
    };
    let fortran = value("fortran_order")?;
    if fortran.starts_with("True") {
        return Err(
            "the array is in Fortran order; expected C order (save numpy.ascontiguousarray(a))"
                .to_string(),
        );
    }
    if !fortran.starts_with("False") {
        return Err("the .npy header's 'fortran_order' is not True or False".to_string());
    }
    let shape = value("shape")?;
    let inner = shape
        .strip_prefix('(')
        .and_then(|s| s.split(')').next())
        .ok_or_else(|| "the .npy header's 'shape' is not a tuple".to_string())?;
    let dims: Vec<&str> = inner
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect();
    let parsed: Result<Vec<u64>, _> = dims.iter().map(|d| d.parse::<u64>()).collect();
    match parsed.as_deref() {
        Ok([rows, c]) if *c == columns => Ok((dtype, *rows)),
        _ if columns == 4 => Err(format!(
            "the array has shape ({}); expected (N, 4): one row per sample, columns vx1, vx2, \
             vy1, vy2",
            shown(inner)
        )),
        _ => Err(format!(
            "the array has shape ({}); expected (N, {columns}): one row per sample, each \
             sensor's vx1, vx2, vy1, vy2 in the rig's order",
            shown(inner)
        )),
    }
}

/// The header of a little-endian float64 `.npy` array of shape `(rows, 4)`,
/// C order (format version 1.0, padded to 64 bytes).
pub fn npy_header(rows: u64) -> Vec<u8> {
    npy_header_columns(rows, 4)
}

/// The header of a little-endian float64 `.npy` array of shape
/// `(rows, columns)`, C order (format version 1.0, padded to 64 bytes).
pub fn npy_header_columns(rows: u64, columns: u64) -> Vec<u8> {
    let dict =
        format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({rows}, {columns}), }}");
    let mut header = dict.into_bytes();
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(b' ');
    }
    header.push(b'\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    // The dictionary of a (u64, 4) shape stays far below 65535 bytes.
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(&header);
    out
}

/// Writes `frames` as rows of a `.npy` array (after [`npy_header`]).
pub fn write_npy_frames(w: &mut impl std::io::Write, frames: &[Frame]) -> std::io::Result<()> {
    for frame in frames {
        for v in frame {
            w.write_all(&v.to_le_bytes())?;
        }
    }
    Ok(())
}

/// The header line of raw.csv as psdcal writes it.
pub const RAW_CSV_HEADER: &str = "t_s,vx1,vx2,vy1,vy2";

/// Writes `frames` as raw.csv rows, the first at sample `first` of a
/// recording sampled at `rate_hz` (`t_s = n / rate`).
pub fn write_csv_frames(
    w: &mut impl std::io::Write,
    first: u64,
    rate_hz: f64,
    frames: &[Frame],
) -> std::io::Result<()> {
    use crate::number_text::number_text;
    for (i, f) in frames.iter().enumerate() {
        let t = (first + i as u64) as f64 / rate_hz;
        writeln!(
            w,
            "{},{},{},{},{}",
            number_text(t),
            number_text(f[0]),
            number_text(f[1]),
            number_text(f[2]),
            number_text(f[3])
        )?;
    }
    Ok(())
}
