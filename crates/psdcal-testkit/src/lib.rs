//! # psdcal-testkit
//!
//! Test support shared by psdcal's crates (a dev-dependency only, never
//! published): the templates, the seeded template-pose draws and the
//! synthetic observations that the tests of psdcal-calib and psdcal-locate
//! build their scenarios from.
//!
//! It depends on `psdcal-model` only, so it returns plain data (poses,
//! points per image): each crate's own test support turns them into its
//! types (`psdcal_calib::CalibrationData`, …). Noise is drawn from any
//! [`rand::distr::Distribution`] the caller passes (a `rand_distr::Normal`
//! in the tests), always in the same order (image by image, LED by LED, x
//! then y), so a seed gives the same data wherever it is used.
//!
//! - [`templates`]: `scatter14` (defined once, in
//!   [`psdcal_model::paper_setup`]), its 20-LED extension, a 5 × 5 grid with
//!   declared lines;
//! - [`poses`]: `sensor_from_template` poses whose images cover the sensor;
//! - [`observe`]: the measured (or ideal) points of a template in given
//!   poses, and point noise;
//! - [`poly_stage`]: [`PolyField`], a test-only model stage with a large
//!   parameter block (a polynomial displacement field, 2n² coefficients);
//! - [`wide`]: [`WideScenario`], scenarios drawn far wider than the
//!   simulator's defaults (both lenses jittered, PSD distortion of either
//!   sign, 9–20 images tilted 5°–45°, partial coverage, noise-free to
//!   beyond 30 dB), for judging the calibration's search;
//! - [`svg`]: the polylines of a report's SVG, read back.
#![warn(missing_docs)]

pub mod observe;
pub mod poly_stage;
pub mod poses;
pub mod svg;
pub mod templates;
pub mod wide;

pub use observe::{add_noise, image_points, PointKind};
pub use poly_stage::PolyField;
pub use poses::{
    aimed_grid_poses, aimed_pose, covering_poses, fits, perturbed, points_in_view, HALF_SIDE_MM,
};
pub use psdcal_model::paper_setup::{scatter14, SCATTER14_MM};
pub use templates::{grid75, scatter, EXTRA_MM};
pub use wide::{WideImage, WideScenario};
