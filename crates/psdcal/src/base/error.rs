//! The facade's error: every failure of the lower crates, and the few of
//! its own, each with a message that says what happened.

use std::path::PathBuf;

use psdcal_calib::CalibError;
use psdcal_io::IoError;
use psdcal_locate::LocateError;
use psdcal_model::ModelError;
use psdcal_report::ReportError;
use psdcal_sim::SimError;
use thiserror::Error;

/// Everything that can stop a psdcal job.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read, parsed, validated or written (the message
    /// names file, line and column).
    #[error(transparent)]
    Io(#[from] IoError),
    /// The calibration itself failed (no convergence, degenerate data).
    #[error("calibration failed")]
    Calibrate(#[source] CalibError),
    /// The calibration of a data set read from files failed: the files
    /// named, then the cause.
    #[error("calibration failed: data {data}")]
    CalibrateData {
        /// The data set's files (template, points, gains), comma-separated.
        data: String,
        /// Why.
        #[source]
        source: CalibError,
    },
    /// Another estimation failed (e.g. the electrical gains).
    #[error(transparent)]
    Estimate(#[from] CalibError),
    /// Angles of arrival, positions or maps could not be computed.
    #[error(transparent)]
    Locate(#[from] LocateError),
    /// The sensor model could not be evaluated.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A simulation could not run.
    #[error(transparent)]
    Simulation(#[from] SimError),
    /// A network calibration could not be done.
    #[error(transparent)]
    Network(#[from] psdcal_network::NetworkError),
    /// A plot or page could not be drawn.
    #[error(transparent)]
    Report(#[from] ReportError),
    /// A calibration whose valid region (docs/model.md §8.2) does not
    /// contain its own data: the fitted correction folds over where the
    /// points are, so it cannot answer there. Refused, not written.
    #[error(
        "the calibration is refused: its distortion correction folds over inside its own data \
         ({outside} of {points} points lie outside its valid region, the nearest fold {fold_mm:.3} \
         mm from the optical centre; first: {first}). Past a fold the model has no unique \
         answer; fit fewer distortion terms (--fit), check the data for outliers, or drop the \
         points far off the centre"
    )]
    DataOutsideValidRegion {
        /// Points outside the region.
        outside: usize,
        /// Points of the data.
        points: usize,
        /// Distance of the nearest fold from the optical centre, mm.
        fold_mm: f64,
        /// The first point outside: image, LED, position and distances.
        first: String,
    },
    /// The images contradict one LED of the template (psdcal-calib's
    /// misplaced-LED check, with the LED's identifier and line).
    #[error(
        "calibration failed: the images contradict LED '{led}' of {template} (line {line}): \
         without it, each image's homography fits {score:.1} times better, in {images} images \
         (without the next LED: {next_score:.2} times). Check its X_mm, Y_mm in the template and \
         its identifier in the observations (the fit alone said: {cause})"
    )]
    MisplacedLed {
        /// The LED's identifier.
        led: String,
        /// The template file.
        template: String,
        /// The LED's line in it.
        line: usize,
        /// How many times better the images fit without it (median).
        score: f64,
        /// The same for the next LED.
        next_score: f64,
        /// Images that scored it.
        images: usize,
        /// What the calibration said without the check.
        cause: String,
    },
    /// Data points outside the scanned hull of the PSD map given to the
    /// calibration (docs/model.md §8.3): the map is not known there.
    #[error(
        "{map}: {outside} of {points} data points lie outside the PSD map's scanned area (first: \
         {first}); the map is known only inside its scan's hull: scan the whole area the data \
         cover, or calibrate without --psd-map"
    )]
    DataOutsidePsdMap {
        /// The map file.
        map: String,
        /// Points outside.
        outside: usize,
        /// Points of the data.
        points: usize,
        /// The first point outside: image, LED and position.
        first: String,
    },
    /// Options that cannot work together or values out of range.
    #[error("{0}")]
    Options(String),
    /// The input has nothing this job can use (the text says what).
    #[error("{0}")]
    Input(String),
    /// An output folder cannot be created or written.
    #[error("{message}")]
    OutputFolder {
        /// The folder.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A long job was interrupted before it wrote anything.
    #[error("the study was interrupted; nothing was written")]
    Interrupted,
}

/// The facade's result.
pub type Result<T, E = Error> = std::result::Result<T, E>;
