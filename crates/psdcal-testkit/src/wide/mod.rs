//! Wide calibration scenarios: a draw far broader than the simulator's
//! defaults (psdcal-sim's paper set-up) or [`crate::covering_poses`], for
//! judging the calibration's search on data it was not tuned on.
//!
//! A scenario is drawn from its index alone (a ChaCha8 stream seeded with
//! [`WIDE_SEED_BASE`]` + index`), in a fixed order:
//!
//! 1. the sensor ([`sensor`]): lens 1 (f ≈ 25 mm) or 2 (f ≈ 8 mm), each
//!    parameter jittered around the paper's lens, and a PSD distortion `l1`
//!    of either sign in half of the scenarios;
//! 2. the template: `scatter14` scaled by a factor in 0.5–2;
//! 3. the images ([`poses`]): 9–20 poses tilted 5°–45°, at distances that
//!    make the template cover 30–90 % of the active area, aimed anywhere
//!    inside a region of the sensor drawn per scenario (so the images may
//!    cover only part of it); LEDs that fall off the active area are
//!    dropped, and a pose is redrawn until it keeps at least
//!    [`MIN_POINTS_PER_IMAGE`] LEDs;
//! 4. the point noise ([`noise`]): noise-free in 20 % of the scenarios,
//!    otherwise Gaussian with σ log-uniform in 1e-5–1e-2 mm.
//!
//! Measured points go through the full model: the ideal pinhole point, then
//! the inverse of the measured → ideal correction (`Model::project_to_tolerance`,
//! Newton to 1e-12 mm), then the noise. The scenario holds plain data
//! (psdcal-testkit depends on psdcal-model only): each crate's test support
//! turns the points into its own data type.

pub mod noise;
pub mod poses;
mod scenario;
pub mod sensor;

pub use noise::{draw_sigma, snr_db_equivalent};
pub use poses::{draw_region, draw_view, AimRegion, WideView};
pub use scenario::{WideImage, WideScenario};
pub use sensor::{draw_sensor, Lens};

/// The base of the scenarios' seeds: scenario `index` draws from
/// `ChaCha8Rng::seed_from_u64(WIDE_SEED_BASE + index)`.
pub const WIDE_SEED_BASE: u64 = 0x0077_1de0_0000;

/// Half-side of the active area, mm (the default 9 × 9 mm PSD): a measured
/// point must lie strictly inside ±this on both axes to be kept.
pub const ACTIVE_HALF_SIDE_MM: f64 = 4.5;

/// The fewest LEDs an image keeps (images with fewer are redrawn).
pub const MIN_POINTS_PER_IMAGE: usize = 6;
