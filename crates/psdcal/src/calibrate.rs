//! Calibrating a data set: the result, its calibration.json record, the
//! residuals and the printable report, and writing them.

use std::path::Path;
use std::sync::OnceLock;

use psdcal_calib::CalibrationResult;
use psdcal_io::{write_calibration, Calibration};

use crate::convert;
use crate::dataset::DataSet;
use crate::error::{Error, Result};
use crate::fit_report::FitReport;
use crate::options::CalibrationOptions;
use crate::provenance::provenance;
use crate::residuals::ResidualTable;

/// A calibrated data set.
#[derive(Debug, Clone)]
pub struct Calibrated {
    /// psdcal-calib's result.
    pub result: CalibrationResult,
    /// The calibration.json record (version 2, with provenance).
    pub record: Calibration,
    /// The printable view of the result.
    pub report: FitReport,
    /// Every point's residuals, computed on first use ([`Self::residuals`]):
    /// a projection per point that a plain calibration does not need.
    residuals: OnceLock<ResidualTable>,
    /// The calibrated images' identifiers, in the order of `result.poses`.
    image_ids: Vec<String>,
}

/// Calibrates `set` with `options`. The record's provenance lists the data
/// set's input files; its command is empty until [`Calibrated::set_command`].
pub fn calibrate(set: &DataSet, options: &CalibrationOptions) -> Result<Calibrated> {
    options
        .check(set.signals.is_some(), set.known_gains.is_some())
        .map_err(Error::Options)?;
    let data = convert::calibration_data(set, options.fit_gains);
    let result = psdcal_calib::calibrate(&data, &convert::calibrate_options(options))
        .map_err(Error::Calibrate)?;
    let mut record = convert::record(&result, &data, set, options);
    record.provenance = Some(provenance("", options.to_json(), &set.inputs));
    let report = convert::fit_report(&result);
    Ok(Calibrated {
        result,
        record,
        report,
        residuals: OnceLock::new(),
        image_ids: data.images.iter().map(|image| image.id.clone()).collect(),
    })
}

impl Calibrated {
    /// Every point's residuals of `set` (the data set this calibration was
    /// made from), computed once.
    pub fn residuals(&self, set: &DataSet) -> &ResidualTable {
        self.residuals.get_or_init(|| {
            let poses: Vec<(&str, psdcal_model::Pose)> = self
                .image_ids
                .iter()
                .map(String::as_str)
                .zip(self.result.poses.iter().copied())
                .collect();
            ResidualTable::compute(&self.result.model, &poses, &set.template, &set.validated)
        })
    }

    /// Records the command line that made this calibration.
    pub fn set_command(&mut self, command: &str) {
        if let Some(p) = &mut self.record.provenance {
            p.command = command.to_string();
        }
    }

    /// Writes calibration.json and, if asked for, residuals.csv
    /// (atomically).
    pub fn write(&self, set: &DataSet, out: &Path, residuals: Option<&Path>) -> Result<()> {
        write_calibration(out, &self.record)?;
        if let Some(path) = residuals {
            self.residuals(set).write_csv(path, &set.template)?;
        }
        Ok(())
    }

    /// The summary as pretty JSON (what `calibrate --json` prints).
    pub fn summary_json(&self) -> Result<String> {
        serde_json::to_string_pretty(&self.result.summary())
            .map_err(|e| Error::Input(format!("cannot encode the summary: {e}")))
    }
}
