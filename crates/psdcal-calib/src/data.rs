//! The input of a calibration: a planar template of LEDs and, per image
//! (template pose), the measured impact points of the LEDs seen in it
//! (docs/model.md §4).

use nalgebra::Vector2;
use psdcal_model::{Amplitudes, PsdGeometry};

/// One measured impact point of one LED in one image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Index of the LED in [`CalibrationData::template`].
    pub led: usize,
    /// Measured impact point, mm, sensor frame.
    pub measured: Vector2<f64>,
}

/// The observations of one image (one template pose).
#[derive(Debug, Clone, PartialEq)]
pub struct ImageObservations {
    /// The image's identifier, as in the input files.
    pub id: String,
    /// Its points (each LED at most once).
    pub points: Vec<Observation>,
}

/// Everything a calibration is computed from.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationData {
    /// LED positions `(X, Y)` on the template plane, mm.
    pub template: Vec<Vector2<f64>>,
    /// Collinear groups of LEDs (indices into `template`, ≥ 3 each), for the
    /// line-straightness correction; empty when the template declares none.
    pub lines: Vec<Vec<usize>>,
    /// The images.
    pub images: Vec<ImageObservations>,
    /// The PSD's active area.
    pub geometry: PsdGeometry,
    /// The electrode amplitudes behind every point (`[image][point]`, same
    /// order as `images`), when the data came as signals: needed to estimate
    /// the channel gains, which recompute each impact point from its
    /// amplitudes (docs/model.md §1). `measured` then holds the points computed
    /// with the starting gains.
    pub amplitudes: Option<Vec<Vec<Amplitudes>>>,
}

impl CalibrationData {
    /// Whether amplitudes are present for every point.
    pub fn has_amplitudes(&self) -> bool {
        self.amplitudes.as_ref().is_some_and(|a| {
            a.len() == self.images.len()
                && a.iter()
                    .zip(&self.images)
                    .all(|(a, im)| a.len() == im.points.len())
        })
    }

    /// Total number of observed points.
    pub fn point_count(&self) -> usize {
        self.images.iter().map(|i| i.points.len()).sum()
    }
}
