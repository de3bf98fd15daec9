//! Calibrating a data set: the result, its calibration.json record, the
//! residuals and the printable report, and writing them.

use std::path::Path;
use std::sync::OnceLock;

use nalgebra::Vector2;
use psdcal_calib::CalibError;
use psdcal_calib::{CalibrationData, CalibrationResult};
use psdcal_io::{write_calibration, Calibration, ValidRegionRecord};
use psdcal_model::ValidRegion;

use crate::base::error::{Error, Result};
use crate::base::options::CalibrationOptions;
use crate::base::provenance::provenance;
use crate::base::summary::Summary;
use crate::calibration::calibrate_map;
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
    if set.template.is_three_d() {
        return Err(Error::Input(format!(
            "{} has LEDs off the plane Z = 0 (its Z_mm column): calibrate fits a planar \
             template; for surveyed 3-D points use psdcal calibrate-in-situ",
            set.template.source
        )));
    }
    options
        .check(set.signals.is_some(), set.known_gains.is_some())
        .map_err(Error::Options)?;
    let data = convert::calibration_data(set, options.fit_gains);
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
    let mut calibrate_options = convert::calibrate_options(options);
    if let (Some(map), Some(path)) = (&map, &options.psd_map) {
        let points: Vec<_> = data
            .images
            .iter()
            .flat_map(|image| {
                image.points.iter().map(|obs| {
                    let led = set
                        .template
                        .leds
                        .get(obs.led)
                        .map_or_else(|| format!("#{}", obs.led), |l| l.id.clone());
                    (image.id.as_str(), led, obs.measured)
                })
            })
            .collect();
        calibrate_map::check_data_in_hull(map, path, &points)?;
    }
    if let Some(map) = &map {
        calibrate_options.base = calibrate_map::with_map(&calibrate_options.base, map)?;
        if options.refine_psd_map {
            calibrate_options.prior = Some(map.loaded.covariance.clone());
        }
    }
    let mut result = psdcal_calib::calibrate(&data, &calibrate_options).map_err(|e| match e {
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
        e => Error::Calibrate(e),
    })?;
    check_data_in_region(&result, &data, set, &result.valid_region)?;
    let map_stage = match &map {
        Some(map) if options.refine_psd_map => {
            Some(calibrate_map::refined_stage(&mut result, map)?)
        }
        Some(map) => Some(calibrate_map::carry(
            &mut result,
            &data,
            &calibrate_options,
            map,
        )?),
        None => None,
    };
    let mut record = convert::record(&result, &data, set, options);
    record.valid_region = Some(ValidRegionRecord::from_region(&result.valid_region));
    record.psd_map = map_stage;
    record.provenance = Some(provenance("", options.to_json(), &inputs));
    let report = convert::fit_report(&result);
    Ok(Calibrated {
        result,
        record,
        report,
        residuals: OnceLock::new(),
        image_ids: data.images.iter().map(|image| image.id.clone()).collect(),
    })
}

/// Refuses a calibration whose valid region does not contain the measured
/// points it was fitted to (with fitted gains, the points recomputed from the
/// amplitudes through them).
fn check_data_in_region(
    result: &CalibrationResult,
    data: &CalibrationData,
    set: &DataSet,
    region: &ValidRegion,
) -> Result<()> {
    let mut points = Vec::new();
    for (i, image) in data.images.iter().enumerate() {
        for (j, obs) in image.points.iter().enumerate() {
            let amplitudes = data.amplitudes.as_ref().and_then(|a| a.get(i)?.get(j));
            let measured = match (result.model.gains_stage(), amplitudes) {
                (Some(_), Some(a)) => result
                    .model
                    .measured_from_amplitudes(a)
                    .unwrap_or(obs.measured),
                _ => obs.measured,
            };
            let led = set
                .template
                .leds
                .get(obs.led)
                .map_or_else(|| format!("#{}", obs.led), |l| l.id.clone());
            points.push((image.id.as_str(), led, measured));
        }
    }
    refuse_points_outside(region, &points)
}

/// [`Error::DataOutsideValidRegion`] when a point `(image, LED, measured)`
/// lies outside `region`.
fn refuse_points_outside(
    region: &ValidRegion,
    points: &[(&str, String, Vector2<f64>)],
) -> Result<()> {
    let outside: Vec<_> = points
        .iter()
        .filter_map(|(image, led, m)| region.check(m).err().map(|o| (image, led, m, o)))
        .collect();
    let Some((image, led, m, o)) = outside.first() else {
        return Ok(());
    };
    Err(Error::DataOutsideValidRegion {
        outside: outside.len(),
        points: points.len(),
        fold_mm: region.nearest_fold_mm().unwrap_or(o.limit_mm),
        first: format!(
            "image {image}, LED {led} at ({:.4}, {:.4}) mm, {:.4} mm from the centre where the \
             region ends at {:.4} mm",
            m.x, m.y, o.distance_mm, o.limit_mm
        ),
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

#[cfg(test)]
mod tests {
    use psdcal_model::{PsdGeometry, SensorModel};

    use super::*;

    /// Data past the fold of k1 = −0.02 mm⁻² about (0.5, −0.7) (r* =
    /// 1/√(3 · 0.02) = 4.08 mm) are refused with the count and the first
    /// point; data inside pass.
    #[test]
    fn data_past_the_fold_are_refused() {
        let mut model = SensorModel::pinhole(8.0, 0.5, -0.7);
        model.distortion.k1 = -0.02;
        let region = ValidRegion::of_sensor_model(&model, &PsdGeometry::default());
        let inside = vec![
            ("1", "a".to_string(), Vector2::new(0.5, -0.7)),
            ("1", "b".to_string(), Vector2::new(3.0, 1.0)),
        ];
        assert!(refuse_points_outside(&region, &inside).is_ok());
        let mut data = inside.clone();
        data.push(("2", "c".to_string(), Vector2::new(-4.5, 4.5)));
        data.push(("3", "d".to_string(), Vector2::new(4.5, -4.5)));
        let e = refuse_points_outside(&region, &data).unwrap_err();
        let Error::DataOutsideValidRegion {
            outside,
            points,
            fold_mm,
            ..
        } = &e
        else {
            panic!("{e}")
        };
        assert_eq!((*outside, *points), (2, 4));
        assert!((fold_mm - 1.0 / (3.0f64 * 0.02).sqrt()).abs() < 1e-9);
        let text = e.to_string();
        assert!(
            text.contains("2 of 4 points lie outside its valid region"),
            "{text}"
        );
        assert!(
            text.contains("image 2, LED c at (-4.5000, 4.5000) mm, 7.2139 mm"),
            "{text}"
        );
        // A non-folding calibration accepts the same data.
        let plain =
            ValidRegion::of_sensor_model(&SensorModel::paper_lens2(), &PsdGeometry::default());
        assert!(refuse_points_outside(&plain, &data).is_ok());
    }
}
