//! Calibrating a data set: the result, its calibration.json record, the
//! residuals and the printable report, and writing them.

use std::io::Write;
use std::path::Path;
use std::sync::OnceLock;

use psdcal_calib::CalibError;
use psdcal_calib::{CalibrationData, CalibrationResult, DataPoint};
use psdcal_io::{Calibration, PendingFile, ValidRegionRecord};

use crate::base::error::{Error, Result};
use crate::base::options::CalibrationOptions;
use crate::base::provenance::provenance;
use crate::base::provenance::InputHashes;
use crate::base::summary::Summary;
use crate::calibration::calibrate_map::{self, MapInput};
use crate::calibration::convert;
use crate::calibration::fit_report::FitReport;
use crate::calibration::residuals::ResidualTable;
use crate::dataset::data_set::DataSet;

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
    check_options(set, options)?;
    // The data set's files, and the map's when there is one (hashed as read).
    let mut inputs = set.inputs.clone();
    let map = match &options.psd_map {
        Some(path) => Some(calibrate_map::load(
            path,
            &set.options.geometry,
            set.options.limits,
            &mut inputs,
        )?),
        None => None,
    };
    calibrate_with_map(set, options, map, &inputs)
}

/// [`calibrate`] with the PSD map already read (or made in memory): the
/// record's provenance lists `inputs`.
pub(crate) fn calibrate_with_map(
    set: &DataSet,
    options: &CalibrationOptions,
    map: Option<MapInput>,
    inputs: &InputHashes,
) -> Result<Calibrated> {
    check_options(set, options)?;
    let data = convert::calibration_data(set, options.fit_gains);
    let mut calibrate_options = convert::calibrate_options(options);
    if let Some(map) = &map {
        calibrate_options.base = calibrate_map::with_map(&calibrate_options.base, map)?;
        if options.refine_psd_map {
            calibrate_options.prior = Some(map.loaded.covariance.clone());
        } else {
            calibrate_options.fixed_covariance = Some(map.loaded.covariance.clone());
        }
    }
    let result = psdcal_calib::calibrate(&data, &calibrate_options)
        .map_err(|e| calibration_error(e, set, &data, map.as_ref().map(|m| m.source.as_str())))?;
    let map_stage = match (&map, &result.block) {
        (Some(map), Some(block)) => Some(calibrate_map::stage_record(map, block)),
        _ => None,
    };
    let mut record = convert::record(&result, &data, set, options);
    record.valid_region = Some(ValidRegionRecord::from_region(&result.valid_region));
    record.psd_map = map_stage;
    record.provenance = Some(provenance("", options.to_json(), inputs));
    let report = convert::fit_report(&result);
    Ok(Calibrated {
        result,
        record,
        report,
        residuals: OnceLock::new(),
        image_ids: data.images.iter().map(|image| image.id.clone()).collect(),
    })
}

/// A planar data set, and the options against it (before any file is
/// read).
fn check_options(set: &DataSet, options: &CalibrationOptions) -> Result<()> {
    if set.template.is_three_d() {
        return Err(Error::Input(format!(
            "{} has LEDs off the plane Z = 0 (its Z_mm column): calibrate fits a planar \
             template; for surveyed 3-D points use psdcal calibrate-in-situ",
            set.template.source
        )));
    }
    options
        .check(set.signals.is_some(), set.known_gains.is_some())
        .map_err(Error::Options)
}

/// psdcal-calib's refusal in the data set's own names: the misplaced LED
/// by identifier and line, a point by its image and LED.
fn calibration_error(
    e: CalibError,
    set: &DataSet,
    data: &CalibrationData,
    map_source: Option<&str>,
) -> Error {
    let point_text = |p: &DataPoint| {
        let image = &data.images[p.image];
        let led = image.points[p.point].led;
        let led = set
            .template
            .leds
            .get(led)
            .map_or_else(|| format!("#{led}"), |l| l.id.clone());
        format!(
            "image {}, LED {led} at ({:.4}, {:.4}) mm",
            image.id, p.measured.x, p.measured.y
        )
    };
    match e {
        CalibError::MisplacedLed {
            led,
            score,
            next_score,
            images,
            cause,
        } if led < set.template.leds.len() => Error::MisplacedLed {
            led: set.template.leds[led].id.clone(),
            template: set.template.source.clone(),
            line: set.template.leds[led].line_no,
            score,
            next_score,
            images,
            cause,
        },
        CalibError::DataOutsideDomain {
            outside,
            points,
            first,
        } => match map_source {
            Some(map) => Error::DataOutsidePsdMap {
                map: map.to_string(),
                outside,
                points,
                first: point_text(&first),
            },
            None => of_data(set, e),
        },
        CalibError::DataOutsideValidRegion {
            outside,
            points,
            fold_mm,
            first,
            distance_mm,
            limit_mm,
        } => Error::DataOutsideValidRegion {
            outside,
            points,
            fold_mm,
            first: format!(
                "{}, {distance_mm:.4} mm from the centre where the region ends at {limit_mm:.4} mm",
                point_text(&first)
            ),
        },
        e => of_data(set, e),
    }
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

    /// Writes calibration.json and, if asked for, residuals.csv, creating
    /// their folders: both are written to temporary files first and
    /// renamed only once both were written (residuals.csv first), so a
    /// failure (a full disk) leaves the existing files as they were.
    pub fn write(&self, set: &DataSet, out: &Path, residuals: Option<&Path>) -> Result<()> {
        for path in std::iter::once(out).chain(residuals) {
            create_parent(path)?;
        }
        let text = self.record.to_json_string(&out.display().to_string())?;
        let calibration = PendingFile::write(out, |w| w.write_all(text.as_bytes()))?;
        if let Some(path) = residuals {
            let table = self.residuals(set);
            PendingFile::write(path, |w| table.write_rows(w, &set.template))?.commit()?;
        }
        Ok(calibration.commit()?)
    }

    /// The warnings of [`Self::summary`] alone (the fit's warnings, then
    /// its diagnostics), without building its text and JSON.
    pub fn warnings(&self) -> Vec<String> {
        let diagnostics = self.report.diagnostics.iter().map(|d| &d.message);
        self.report
            .warnings
            .iter()
            .chain(diagnostics)
            .cloned()
            .collect()
    }

    /// The summary after writing to `out` (and `residuals`): the fit's
    /// report as text, the result's summary as JSON, and the fit's warnings
    /// and diagnostics.
    pub fn summary(&self, out: &Path, residuals: Option<&Path>) -> Result<Summary> {
        let json = serde_json::to_value(self.result.summary())
            .map_err(|e| Error::Input(format!("cannot encode the summary: {e}")))?;
        let diagnostics = self.report.diagnostics.iter().map(|d| &d.message);
        Ok(Summary::new(self.report.to_string(), json)
            .wrote(std::iter::once(out).chain(residuals))
            .warn(&self.report.warnings)
            .warn(diagnostics))
    }
}

/// A calibration error naming the data set's files (when it was read from
/// files).
fn of_data(set: &DataSet, e: CalibError) -> Error {
    let files: Vec<&str> = set.inputs.0.iter().map(|f| f.path.as_str()).collect();
    if files.is_empty() {
        return Error::Calibrate(e);
    }
    Error::CalibrateData {
        data: files.join(", "),
        source: e,
    }
}

/// Creates the folder a file is written in, if missing.
fn create_parent(path: &Path) -> Result<()> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => {
            std::fs::create_dir_all(dir).map_err(|e| Error::OutputFolder {
                path: dir.to_path_buf(),
                message: format!("cannot create the output folder {}: {e}", dir.display()),
            })
        }
        _ => Ok(()),
    }
}
