//! Bounds on what psdcal reads (docs/formats.md, "Limits"): no input can
//! make a reader use unbounded memory or print an unbounded message.
//!
//! - A **line** of a CSV file holds at most [`MAX_LINE_BYTES`] bytes.
//! - A **file** read whole (the CSV files of a data set, calibration.json,
//!   gains.json, rig.json, truth.json, rig_points.csv) holds at most
//!   [`ReadLimits::max_file_bytes`] bytes: 512 MiB unless the caller passes
//!   other [`ReadLimits`] to the reader (`psdcal --max-input-mb`). Streamed tables
//!   (points.csv for `correct`, `aoa` and `locate` on a plane) are read row
//!   by row in constant memory and have no size limit.
//! - A message quotes at most [`MAX_EXCERPT_CHARS`] characters of a file.
//!
//! Future readers (raw recordings) use the same bounds: [`read_bounded`] for
//! whole files, [`crate::csv_lines`]'s line reader for text.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::error::IoError;
use crate::location::Location;

/// The longest CSV line accepted, bytes (1 MiB).
pub const MAX_LINE_BYTES: usize = 1 << 20;
/// The default largest file read whole, bytes (512 MiB).
pub const DEFAULT_MAX_FILE_BYTES: u64 = 512 << 20;
/// The most characters of a file's content quoted in a message.
pub const MAX_EXCERPT_CHARS: usize = 60;

/// The bounds a reader of a whole file is given (default: 512 MiB), passed
/// to each reader that takes them (`read_with`, `from_reader_with`, …); the
/// readers without them use the default.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReadLimits {
    /// The largest file read whole, bytes.
    pub max_file_bytes: u64,
}

impl Default for ReadLimits {
    fn default() -> Self {
        Self {
            max_file_bytes: DEFAULT_MAX_FILE_BYTES,
        }
    }
}

impl ReadLimits {
    /// At most `mib` MiB per file read whole (`psdcal --max-input-mb`; at
    /// least 1 KiB).
    pub fn from_mib(mib: u64) -> Self {
        Self {
            max_file_bytes: (mib << 20).max(1024),
        }
    }
}

/// The error of a file past the size limit.
pub(crate) fn too_large(source: &str, limit: u64) -> IoError {
    IoError::TooLarge {
        at: Location::file(source),
        message: format!(
            "the file is larger than {}, the largest file read whole",
            bytes_text(limit)
        ),
    }
}

/// `512 MiB`, `1.5 KiB`, `100 bytes`.
pub(crate) fn bytes_text(bytes: u64) -> String {
    const MIB: u64 = 1 << 20;
    if bytes >= MIB && bytes.is_multiple_of(MIB) {
        format!("{} MiB", bytes / MIB)
    } else if bytes >= 1024 {
        format!("{:.1} KiB", bytes as f64 / 1024.0)
    } else {
        format!("{bytes} bytes")
    }
}

/// Reads a whole file, refusing one past `limits`' [`ReadLimits::max_file_bytes`]
/// (counted while reading, so devices and pipes are bounded too).
pub fn read_bounded(path: &Path, limits: ReadLimits) -> Result<Vec<u8>, IoError> {
    let source = path.display().to_string();
    let file = File::open(path).map_err(|e| IoError::Read {
        file: source.clone(),
        source: e,
    })?;
    read_all_bounded(&source, file, limits)
}

/// Reads everything from `reader`, refusing more than `limits`'
/// [`ReadLimits::max_file_bytes`].
pub fn read_all_bounded(
    source: &str,
    reader: impl Read,
    limits: ReadLimits,
) -> Result<Vec<u8>, IoError> {
    read_all_limited(source, reader, limits.max_file_bytes)
}

/// A file read whole (within `limits`) as UTF-8 text.
pub(crate) fn read_text(path: &Path, limits: ReadLimits) -> Result<String, IoError> {
    let source = path.display().to_string();
    utf8_text(&source, read_bounded(path, limits)?)
}

/// [`read_text`] from a reader; `source` names it in messages.
pub(crate) fn read_text_from(
    source: &str,
    reader: impl Read,
    limits: ReadLimits,
) -> Result<String, IoError> {
    utf8_text(source, read_all_bounded(source, reader, limits)?)
}

fn utf8_text(source: &str, bytes: Vec<u8>) -> Result<String, IoError> {
    String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        IoError::Encoding {
            at: Location::file(source),
            message: format!(
                "the byte at offset {offset} is not UTF-8; expected a UTF-8 JSON file"
            ),
        }
    })
}

/// Reads everything from `reader`, refusing more than `limit` bytes.
fn read_all_limited(source: &str, reader: impl Read, limit: u64) -> Result<Vec<u8>, IoError> {
    let mut bytes = Vec::new();
    reader
        .take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| IoError::Read {
            file: source.to_string(),
            source: e,
        })?;
    if bytes.len() as u64 > limit {
        return Err(too_large(source, limit));
    }
    Ok(bytes)
}

/// Text shown in a message: at most [`MAX_EXCERPT_CHARS`] characters, then
/// `…` when shortened.
pub(crate) fn excerpt(text: &str) -> String {
    let mut shown: String = text.chars().take(MAX_EXCERPT_CHARS).collect();
    if text.chars().nth(MAX_EXCERPT_CHARS).is_some() {
        shown.push('…');
    }
    shown
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounded_reads_refuse_endless_input() {
        let e = read_all_limited("zero", std::io::repeat(0), 4 << 20).unwrap_err();
        assert!(matches!(e, IoError::TooLarge { .. }), "{e}");
        assert_eq!(
            e.to_string(),
            "zero: the file is larger than 4 MiB, the largest file read whole"
        );
        assert_eq!(read_all_limited("s", &b"abc"[..], 3).unwrap(), b"abc");
        assert!(read_all_limited("s", &b"abcd"[..], 3).is_err());
        assert_eq!(ReadLimits::default().max_file_bytes, DEFAULT_MAX_FILE_BYTES);
        assert_eq!(ReadLimits::from_mib(3).max_file_bytes, 3 << 20);
    }

    #[test]
    fn two_limits_in_one_process_are_each_honoured() {
        let dir = std::env::temp_dir().join(format!("psdcal-limits-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("two_kib.bin");
        std::fs::write(&path, vec![b'x'; 2048]).unwrap();
        let small = ReadLimits {
            max_file_bytes: 1024,
        };
        let large = ReadLimits::from_mib(1);
        let (a, b) = std::thread::scope(|s| {
            let a = s.spawn(|| read_bounded(&path, small));
            let b = s.spawn(|| read_bounded(&path, large));
            (a.join().unwrap(), b.join().unwrap())
        });
        assert_eq!(
            a.unwrap_err().to_string(),
            format!(
                "{}: the file is larger than 1.0 KiB, the largest file read whole",
                path.display()
            )
        );
        assert_eq!(b.unwrap().len(), 2048);
        // One after the other, on one thread, too.
        assert!(read_bounded(&path, small).is_err());
        assert!(read_bounded(&path, ReadLimits::default()).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn excerpts_are_short() {
        let long = "é".repeat(1000);
        let shown = excerpt(&long);
        assert_eq!(shown.chars().count(), MAX_EXCERPT_CHARS + 1);
        assert!(shown.ends_with('…'));
        assert_eq!(excerpt("a, b"), "a, b");
        assert_eq!(bytes_text(1 << 20), "1 MiB");
        assert_eq!(bytes_text(1536), "1.5 KiB");
    }
}
