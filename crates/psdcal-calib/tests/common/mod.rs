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
#![allow(dead_code)]

use nalgebra::{Rotation3, Unit, Vector2, Vector3};
use psdcal_calib::{CalibrationData, ImageObservations, Observation};
use psdcal_model::{Pose, PsdGeometry, SensorModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Half-side of the square every measured point must fall in, mm.
pub const HALF_SIDE_MM: f64 = 4.4;

/// 14 LEDs (mm), no three collinear.
pub fn unaligned_template() -> Vec<Vector2<f64>> {
    [
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
    ]
    .iter()
    .map(|&(x, y)| Vector2::new(x, y))
    .collect()
}

/// A 5 × 5 grid (pitch 75 mm, ±150 mm) and its 12 lines: 5 rows, 5 columns,
/// 2 diagonals.
pub fn grid_template() -> (Vec<Vector2<f64>>, Vec<Vec<usize>>) {
    let pts = (0..5)
        .flat_map(|i| {
            (0..5).map(move |j| Vector2::new(-150.0 + 75.0 * j as f64, -150.0 + 75.0 * i as f64))
        })
        .collect();
    let mut lines: Vec<Vec<usize>> = Vec::new();
    for i in 0..5 {
        lines.push((0..5).map(|j| 5 * i + j).collect());
        lines.push((0..5).map(|j| 5 * j + i).collect());
    }
    lines.push((0..5).map(|k| 6 * k).collect());
    lines.push((0..5).map(|k| 4 * (k + 1)).collect());
    (pts, lines)
}

/// Pose with the template centre seen at `aim` (ideal image, mm) at depth
/// `z`, tilted by `tilt` about the in-plane axis at angle `axis`, rolled by
/// `roll` about the template normal.
pub fn aimed_pose(
    model: &SensorModel,
    aim: Vector2<f64>,
    z: f64,
    tilt: f64,
    axis: f64,
    roll: f64,
) -> Pose {
    let k = &model.intrinsics;
    let tilt_rot = Rotation3::from_axis_angle(
        &Unit::new_normalize(Vector3::new(axis.cos(), axis.sin(), 0.0)),
        tilt,
    );
    let roll_rot = Rotation3::from_axis_angle(&Vector3::z_axis(), roll);
    let r = (tilt_rot * roll_rot).into_inner();
    let t = Vector3::new((aim.x - k.cx) * z / k.f, (aim.y - k.cy) * z / k.f, z);
    Pose::from_rotation(&r, t)
}

/// Whether every template point of `pose` projects (with distortion) inside
/// ±[`HALF_SIDE_MM`].
pub fn fits(model: &SensorModel, pose: &Pose, template: &[Vector2<f64>]) -> bool {
    template.iter().all(|p| match model.project(pose, p) {
        Ok(m) => m.x.abs() <= HALF_SIDE_MM && m.y.abs() <= HALF_SIDE_MM,
        Err(_) => false,
    })
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
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let cell = Vector2::new((k % 3) as f64 - 1.0, ((k / 3) % 3) as f64 - 1.0);
        let mut reach = 2.8;
        'aim: loop {
            for _ in 0..400 {
                let z = rng.random_range(700.0..1500.0);
                let aim = cell * reach
                    + Vector2::new(rng.random_range(-0.2..0.2), rng.random_range(-0.2..0.2));
                let pose = if max_tilt > 0.0 {
                    let tilt = rng.random_range(0.3 * max_tilt..max_tilt);
                    let axis = rng.random_range(0.0..std::f64::consts::TAU);
                    let roll = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
                    aimed_pose(model, aim, z, tilt, axis, roll)
                } else {
                    aimed_pose(model, aim, z, 0.0, 0.0, 0.0)
                };
                if fits(model, &pose, template) {
                    out.push(pose);
                    break 'aim;
                }
            }
            reach *= 0.8;
        }
    }
    out
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
    let images = poses
        .iter()
        .enumerate()
        .map(|(i, pose)| ImageObservations {
            id: format!("{}", i + 1),
            points: template
                .iter()
                .enumerate()
                .map(|(led, p)| {
                    let mut m = if ideal {
                        model.project_ideal(pose, p).expect("in front")
                    } else {
                        model.project(pose, p).expect("projectable")
                    };
                    if sigma_mm > 0.0 {
                        m += Vector2::new(noise.sample(&mut rng), noise.sample(&mut rng));
                    }
                    Observation { led, measured: m }
                })
                .collect(),
        })
        .collect();
    CalibrationData {
        amplitudes: None,
        template: template.to_vec(),
        lines: lines.to_vec(),
        images,
        geometry: PsdGeometry::default(),
    }
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
