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
    /// Hashes `path` and adds it (a file that cannot be read again is
    /// listed with an empty hash: it was read once already, so this only
    /// happens when it changed under us).
    pub fn add(&mut self, path: &Path) {
        let sha256 = std::fs::read(path).map_or_else(|_| String::new(), |b| sha256_hex(&b));
        self.0.push(InputFile {
            path: path.display().to_string(),
            sha256,
        });
    }
}

/// SHA-256 of `bytes`, lower-case hexadecimal.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
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
