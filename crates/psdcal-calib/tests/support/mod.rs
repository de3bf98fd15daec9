//! Synthetic calibration scenarios for the refinement tests: a 14-LED
//! unaligned template, poses 0.7–1.5 m away tilted up to 30° whose images
//! together cover the sensor, optional Gaussian noise on the measured points.
//! The templates, the pose draw and the observations come from
//! `psdcal-testkit`; this module turns them into `CalibrationData`.
#![allow(dead_code)]

pub mod coverage;
mod data;
pub mod robustness;
pub mod wide;

pub use data::calibration_data;

use nalgebra::Vector2;
use psdcal_calib::CalibrationData;
use psdcal_model::{Param, Pose, SensorModel};
use psdcal_testkit::PointKind;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::Normal;

/// Asserts that every `free` parameter of `got` matches `truth`: relative
/// 1e-6 where the value is not zero, absolute otherwise in the parameter's
/// own scale (1 mm for f, cx, cy; 1e-8 for the distortion coefficients).
pub fn assert_recovered<P: AsRef<str>>(
    name: &str,
    got: &SensorModel,
    truth: &SensorModel,
    free: &[P],
) {
    // Names that are not standard parameters (the gains) are checked elsewhere.
    for p in free.iter().filter_map(|n| n.as_ref().parse::<Param>().ok()) {
        let p = &p;
        let (g, t) = (got.get(*p), truth.get(*p));
        let scale = match p {
            Param::F | Param::Cx | Param::Cy => t.abs().max(1.0),
            _ => t.abs().max(1e-8),
        };
        assert!(
            (g - t).abs() <= 1e-6 * scale,
            "{name}: {p} = {g:e}, truth {t:e}"
        );
    }
}

/// The first `leds` LEDs of the 20-LED template (14 or 20): `scatter14`
/// and six more.
pub fn template(leds: usize) -> Vec<Vector2<f64>> {
    psdcal_testkit::scatter(leds)
}

/// A scenario: the truth and the data it produced.
pub struct Scenario {
    pub truth: SensorModel,
    pub poses: Vec<Pose>,
    pub data: CalibrationData,
}

/// Random poses aimed at a jittered 3 × 3 grid over the sensor (more images
/// cycle through it), 0.7–1.5 m, tilt up to 30° about an axis in the
/// template plane, any roll; a pose is redrawn until every LED falls inside
/// ±4.4 mm.
pub fn poses(truth: &SensorModel, n: usize, rng: &mut ChaCha8Rng) -> Vec<Pose> {
    poses_for(truth, &template(20), n, rng)
}

/// [`poses`] for a given template.
pub fn poses_for(
    truth: &SensorModel,
    template: &[Vector2<f64>],
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<Pose> {
    psdcal_testkit::covering_poses(truth, template, n, rng)
}

/// A scenario with `n` images and point noise of std `sigma_mm` per
/// coordinate, all from `seed`.
pub fn scenario(truth: SensorModel, n: usize, sigma_mm: f64, seed: u64) -> Scenario {
    scenario_with(truth, 14, n, sigma_mm, seed)
}

/// A scenario with a template of `leds` LEDs (14 or 20).
pub fn scenario_with(
    truth: SensorModel,
    leds: usize,
    n: usize,
    sigma_mm: f64,
    seed: u64,
) -> Scenario {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let poses = poses(&truth, n, &mut rng);
    let data = observe_with(&truth, &template(leds), &poses, sigma_mm, &mut rng);
    Scenario { truth, poses, data }
}

/// Measures every LED in every pose, adding Gaussian noise.
pub fn observe(
    truth: &SensorModel,
    poses: &[Pose],
    sigma_mm: f64,
    rng: &mut ChaCha8Rng,
) -> CalibrationData {
    observe_with(truth, &template(14), poses, sigma_mm, rng)
}

/// [`observe`] for a given template.
pub fn observe_with(
    truth: &SensorModel,
    template: &[Vector2<f64>],
    poses: &[Pose],
    sigma_mm: f64,
    rng: &mut ChaCha8Rng,
) -> CalibrationData {
    let noise = Normal::new(0.0, sigma_mm.max(0.0)).expect("valid sigma");
    let mut points = psdcal_testkit::image_points(truth, template, poses, PointKind::Measured);
    if sigma_mm > 0.0 {
        psdcal_testkit::add_noise(&mut points, &noise, rng);
    }
    calibration_data(template, &[], points)
}

/// The truth disturbed: a start for the refinement that is near but not at it.
pub fn perturbed(truth: &SensorModel, poses: &[Pose]) -> (SensorModel, Vec<Pose>) {
    psdcal_testkit::perturbed(truth, poses)
}
