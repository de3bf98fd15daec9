//! Synthetic data for the linear-stage tests (`tests/linear_*.rs`).
//!
//! Two templates: the 14-LED unaligned one of the paper's kind (no three
//! LEDs collinear, within ±150 mm), and a 5 × 5 grid of pitch 75 mm whose
//! rows, columns and two diagonals are declared as lines (for the
//! line-straightness correction). Poses `sensor_from_template`: the template
//! centre aimed at a 3 × 3 grid of sensor positions, 0.7–1.5 m away, tilted
//! up to 30° about a random in-plane axis, any roll; a pose is redrawn (from
//! a fixed-seed ChaCha8 stream) until every LED's measured point lies inside
//! ±4.4 mm, and the aim is pulled towards the centre when no pose fits.
//!
//! The templates, the pose draw and the observations come from
//! `psdcal-testkit`; this module names them as the linear tests use them and
//! turns the points into `CalibrationData`.
#![allow(dead_code)]

#[path = "../support/data.rs"]
mod data;

use nalgebra::Vector2;
use psdcal_calib::CalibrationData;
use psdcal_model::{Pose, SensorModel};
use psdcal_testkit::PointKind;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::Normal;

/// 14 LEDs (mm), no three collinear: `scatter14`.
pub fn unaligned_template() -> Vec<Vector2<f64>> {
    psdcal_testkit::scatter14()
}

/// A 5 × 5 grid (pitch 75 mm, ±150 mm) and its 12 lines: 5 rows, 5 columns,
/// 2 diagonals.
pub fn grid_template() -> (Vec<Vector2<f64>>, Vec<Vec<usize>>) {
    psdcal_testkit::grid75()
}

/// `n` random poses (module documentation) that keep `template` on the sensor.
/// With `max_tilt = 0` the poses are fronto-parallel with `rvec = 0`.
pub fn poses(
    model: &SensorModel,
    template: &[Vector2<f64>],
    n: usize,
    max_tilt: f64,
    seed: u64,
) -> Vec<Pose> {
    psdcal_testkit::aimed_grid_poses(model, template, n, max_tilt, seed)
}

/// The data of `poses`: measured points (`ideal = false`, through the
/// model's distortion) or ideal pinhole points (`ideal = true`), plus
/// Gaussian noise of standard deviation `sigma_mm` (seeded) when positive.
pub fn observe(
    model: &SensorModel,
    template: &[Vector2<f64>],
    lines: &[Vec<usize>],
    poses: &[Pose],
    ideal: bool,
    sigma_mm: f64,
    seed: u64,
) -> CalibrationData {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma_mm.max(1e-300)).expect("valid sigma");
    let kind = if ideal {
        PointKind::Ideal
    } else {
        PointKind::Measured
    };
    let mut points = psdcal_testkit::image_points(model, template, poses, kind);
    if sigma_mm > 0.0 {
        psdcal_testkit::add_noise(&mut points, &noise, &mut rng);
    }
    data::calibration_data(template, lines, points)
}

/// A scenario: the truth and what it produced.
pub struct Scenario {
    /// The true sensor.
    pub truth: SensorModel,
    /// The true poses.
    pub poses: Vec<Pose>,
    /// The observations.
    pub data: CalibrationData,
}

/// Nine noise-free images of the unaligned template (measured points).
pub fn unaligned(truth: SensorModel, seed: u64) -> Scenario {
    let template = unaligned_template();
    let poses = poses(&truth, &template, 9, 30f64.to_radians(), seed);
    let data = observe(&truth, &template, &[], &poses, false, 0.0, 0);
    Scenario { truth, poses, data }
}

/// Nine noise-free images of the grid template with its lines.
pub fn grid(truth: SensorModel, seed: u64) -> Scenario {
    let (template, lines) = grid_template();
    let poses = poses(&truth, &template, 9, 30f64.to_radians(), seed);
    let data = observe(&truth, &template, &lines, &poses, false, 0.0, 0);
    Scenario { truth, poses, data }
}

/// Relative error `|a − b| / |b|`.
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}
