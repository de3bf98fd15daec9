//! A calibration file as a calibrated sensor (calibration.json of either
//! version → `psdcal_locate::CalibratedSensor`).

use std::path::{Path, PathBuf};

use psdcal_io::{read_calibration_with, Calibration, ReadLimits};
use psdcal_locate::CalibratedSensor;

use crate::base::error::Result;
use crate::calibration::convert;

/// A calibration read from a file, and its sensor.
#[derive(Debug, Clone)]
pub struct LoadedSensor {
    /// The file.
    pub path: PathBuf,
    /// Its record.
    pub record: Calibration,
    /// The calibrated sensor: model, active area, gains, covariance.
    pub sensor: CalibratedSensor,
}

impl LoadedSensor {
    /// Reads calibration.json (version 1 or 2).
    pub fn read(path: &Path) -> Result<Self> {
        Self::read_with(path, ReadLimits::default())
    }

    /// [`Self::read`] within `limits` (docs/formats.md, "Limits").
    pub fn read_with(path: &Path, limits: ReadLimits) -> Result<Self> {
        let record = read_calibration_with(path, limits)?;
        let sensor = convert::sensor(&record, path)?;
        Ok(Self {
            path: path.to_path_buf(),
            record,
            sensor,
        })
    }

    /// Whether the calibration has no covariance (nothing was estimated):
    /// the calibration's part of every σ is then 0.
    pub fn lacks_covariance(&self) -> bool {
        self.sensor.covariance.is_empty()
    }
}

/// The calibrated sensor of a record (not read from a file).
pub fn sensor_of(record: &Calibration) -> Result<CalibratedSensor> {
    Ok(convert::sensor(record, Path::new("calibration"))?)
}

/// The warning for a calibration without covariance, if it has none.
pub fn covariance_warning(loaded: &LoadedSensor) -> Option<String> {
    loaded.lacks_covariance().then(|| {
        format!(
            "{} has no covariance (nothing was estimated): the calibration's part of every \
             sigma is 0",
            loaded.path.display()
        )
    })
}

/// Writes `record` as calibration.json at `path` (atomically), as
/// `psdcal calibrate --out` does; refused (before anything is written)
/// when `path` is one of the files the calibration was made from (its
/// provenance's inputs).
pub fn save_calibration(record: &Calibration, path: &Path) -> Result<()> {
    let inputs: Vec<PathBuf> = record
        .provenance
        .iter()
        .flat_map(|p| p.inputs.iter().map(|i| PathBuf::from(&i.path)))
        .collect();
    let named: Vec<(&str, &Path)> = inputs
        .iter()
        .map(|p| ("the data set", p.as_path()))
        .collect();
    psdcal_io::refuse_overwrite(&named, &[("the calibration", path)])?;
    Ok(psdcal_io::write_calibration(path, record)?)
}
