//! Synthetic calibration scenarios for the refinement tests: a 14-LED
//! unaligned template, poses 0.7–1.5 m away tilted up to 30° whose images
//! together cover the sensor, optional Gaussian noise on the measured points.
#![allow(dead_code)]

pub mod robustness;

use nalgebra::{Vector2, Vector3};
use psdcal_calib::{CalibrationData, ImageObservations, Observation};
use psdcal_model::{Param, Pose, PsdGeometry, SensorModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

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

/// 14 LEDs (mm), no three collinear.
pub const TEMPLATE_MM: [(f64, f64); 14] = [
    (-140.0, -120.0),
    (-60.0, -135.0),
    (35.0, -110.0),
    (120.0, -140.0),
    (-120.0, -40.0),
    (-25.0, -55.0),
    (70.0, -30.0),
    (145.0, -60.0),
    (-135.0, 50.0),
    (-50.0, 35.0),
    (40.0, 60.0),
    (130.0, 25.0),
    (-80.0, 130.0),
    (90.0, 140.0),
];

/// Six more LEDs for a 20-LED template (still no three collinear).
pub const EXTRA_MM: [(f64, f64); 6] = [
    (-10.0, -150.0),
    (100.0, 95.0),
    (-150.0, 110.0),
    (15.0, 145.0),
    (150.0, -10.0),
    (-95.0, -95.0),
];

/// The first `leds` LEDs of the 20-LED template (14 or 20).
pub fn template(leds: usize) -> Vec<Vector2<f64>> {
    TEMPLATE_MM
        .iter()
        .chain(EXTRA_MM.iter())
        .take(leds)
        .map(|&(x, y)| Vector2::new(x, y))
        .collect()
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
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let k = out.len() % 9;
        let aim = Vector2::new(-2.6 + 2.6 * (k % 3) as f64, -2.6 + 2.6 * (k / 3) as f64)
            + Vector2::new(rng.random_range(-0.6..0.6), rng.random_range(-0.6..0.6));
        let z: f64 = rng.random_range(700.0..1500.0);
        let tilt: f64 = rng.random_range(0.0..30f64.to_radians());
        let axis_angle: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let roll: f64 = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        let tilt_pose = Pose::new(
            Vector3::new(axis_angle.cos(), axis_angle.sin(), 0.0) * tilt,
            Vector3::zeros(),
        );
        let roll_pose = Pose::new(Vector3::new(0.0, 0.0, roll), Vector3::zeros());
        let rot = tilt_pose.compose(&roll_pose);
        let t = Vector3::new(
            (aim.x - truth.intrinsics.cx) * z / truth.intrinsics.f,
            (aim.y - truth.intrinsics.cy) * z / truth.intrinsics.f,
            z,
        );
        let pose = Pose::new(rot.rvec, t);
        let inside = template.iter().all(|xy| {
            truth
                .project(&pose, xy)
                .map(|m| m.x.abs() < 4.4 && m.y.abs() < 4.4)
                .unwrap_or(false)
        });
        if inside {
            out.push(pose);
        }
    }
    out
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
    let template = template.to_vec();
    let noise = Normal::new(0.0, sigma_mm.max(0.0)).expect("valid sigma");
    let images = poses
        .iter()
        .enumerate()
        .map(|(i, pose)| ImageObservations {
            id: format!("{}", i + 1),
            points: template
                .iter()
                .enumerate()
                .map(|(led, xy)| {
                    let m = truth.project(pose, xy).expect("pose checked");
                    let n = if sigma_mm > 0.0 {
                        Vector2::new(noise.sample(rng), noise.sample(rng))
                    } else {
                        Vector2::zeros()
                    };
                    Observation {
                        led,
                        measured: m + n,
                    }
                })
                .collect(),
        })
        .collect();
    CalibrationData {
        amplitudes: None,
        template,
        lines: Vec::new(),
        images,
        geometry: PsdGeometry::default(),
    }
}

/// The truth disturbed: a start for the refinement that is near but not at it.
pub fn perturbed(truth: &SensorModel, poses: &[Pose]) -> (SensorModel, Vec<Pose>) {
    let mut m = *truth;
    m.intrinsics.f *= 1.04;
    m.intrinsics.cx += 0.15;
    m.intrinsics.cy -= 0.2;
    m.distortion.k1 *= 0.8;
    m.distortion.k2 = 0.0;
    let p = poses
        .iter()
        .map(|p| {
            Pose::new(
                p.rvec + Vector3::new(0.01, -0.015, 0.02),
                p.t + Vector3::new(8.0, -5.0, 30.0),
            )
        })
        .collect();
    (m, p)
}
