//! Where a calibration came from: the inputs' SHA-256, the command line,
//! the options and the time (calibration.json version 2, `provenance`).

use std::path::Path;
use std::time::{SystemTime, UNIX_EPOCH};

use psdcal_io::{InputFile, Provenance};
use sha2::{Digest, Sha256};

/// The input files of a job with their SHA-256, in the order given.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct InputHashes(pub Vec<InputFile>);

impl InputHashes {
    /// Reads `path` once through `parse` (given the path as the source
    /// name for messages and a reader), hashing exactly the bytes the
    /// parser consumed, and adds the file with that hash: what the
    /// provenance records is what was read, even if the file changes later.
    pub fn read<T, E>(
        &mut self,
        path: &Path,
        parse: impl FnOnce(&str, &mut HashingReader<std::fs::File>) -> Result<T, E>,
    ) -> Result<T, E>
    where
        E: From<psdcal_io::IoError>,
    {
        let source = path.display().to_string();
        let file = std::fs::File::open(path).map_err(|e| psdcal_io::IoError::Read {
            file: source.clone(),
            source: e,
        })?;
        let mut reader = HashingReader {
            inner: file,
            hasher: Sha256::new(),
        };
        let parsed = parse(&source, &mut reader)?;
        // Whatever the parser left unread (nothing, for a whole-file
        // parser) still belongs to the file's hash.
        let _ = std::io::copy(&mut reader, &mut std::io::sink());
        self.0.push(InputFile {
            path: source,
            sha256: hex(&reader.hasher.finalize()),
        });
        Ok(parsed)
    }
}

/// A reader that hashes (SHA-256) the bytes read through it
/// ([`InputHashes::read`]).
pub struct HashingReader<R> {
    inner: R,
    hasher: Sha256,
}

impl<R: std::io::Read> std::io::Read for HashingReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }
}

/// SHA-256 of `bytes`, lower-case hexadecimal.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

fn hex(digest: &[u8]) -> String {
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// The provenance of a result made now by `command` with `options`.
pub fn provenance(command: &str, options: serde_json::Value, inputs: &InputHashes) -> Provenance {
    Provenance {
        psdcal_version: env!("CARGO_PKG_VERSION").to_string(),
        command: command.to_string(),
        options,
        inputs: inputs.0.clone(),
        created_utc: utc_iso8601(SystemTime::now()),
    }
}

/// `YYYY-MM-DDThh:mm:ssZ` of a time (times before 1970 read as 1970).
pub fn utc_iso8601(time: SystemTime) -> String {
    let secs = time.duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let days = (secs / 86_400) as i64;
    let rest = secs % 86_400;
    let (y, m, d) = civil_from_days(days);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rest / 3600,
        rest % 3600 / 60,
        rest % 60
    )
}

/// The proleptic Gregorian date of a day count since 1970-01-01 (Howard
/// Hinnant's `civil_from_days`).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;

    #[test]
    fn utc_dates() {
        let at = |s: u64| utc_iso8601(UNIX_EPOCH + Duration::from_secs(s));
        assert_eq!(at(0), "1970-01-01T00:00:00Z");
        assert_eq!(at(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(at(1_709_251_199), "2024-02-29T23:59:59Z");
        assert_eq!(at(4_102_444_800), "2100-01-01T00:00:00Z");
    }

    #[test]
    fn sha256_of_abc() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
