//! Measured points (or electrode amplitudes) → ideal points with a
//! calibration: the table `psdcal correct` writes.

use std::io::{self, Write};
use std::path::Path;

use psdcal_io::{correct_points, read_calibration, write_atomic, Correction, IoError, Points};

use crate::error::Result;

/// A corrected points file.
#[derive(Debug, Clone)]
pub struct Corrected {
    /// The points read.
    pub points: Points,
    /// The corrected points and the warnings.
    pub correction: Correction,
}

/// Corrects the points of `points` with the calibration at `calibration`.
pub fn correct(calibration: &Path, points: &Path) -> Result<Corrected> {
    let calibration = read_calibration(calibration)?;
    let points = Points::read(points)?;
    let correction = correct_points(&points, &calibration)?;
    Ok(Corrected { points, correction })
}

impl Corrected {
    /// Writes the table to `out` atomically, or to standard output.
    pub fn write_to(&self, out: Option<&Path>) -> Result<()> {
        match out {
            Some(path) => Ok(write_atomic(path, |w| {
                self.correction.write_csv(&self.points, w)
            })?),
            None => {
                let mut stdout = io::stdout().lock();
                self.correction
                    .write_csv(&self.points, &mut stdout)
                    .and_then(|()| stdout.flush())
                    .map_err(|source| {
                        IoError::Write {
                            file: "standard output".to_string(),
                            source,
                        }
                        .into()
                    })
            }
        }
    }
}
