//! The template poses of a wide scenario and the LEDs each keeps.
//!
//! Per scenario, an [`AimRegion`]: a square of half-width U(1, 3.5) mm
//! centred U(−1.5, 1.5) mm from the electrical centre on each axis, inside
//! which every image's template origin is aimed (its ideal image point), so
//! that a scenario's images may cover only part of the sensor.
//!
//! Per image, in this order: the coverage `a` ~ U(0.3, 0.9), the fraction
//! of the active area that the template's bounding box would cover seen
//! fronto-parallel (the distance is `z = f √(W H) / √(a Lx Ly)` for a
//! template of bounding box `W × H`; the tilt then shrinks the image by up
//! to cos 45°); the tilt ~ U(5°, 45°) about an in-plane axis at an angle
//! ~ U(0, 2π); the rotation about the optical axis ~ U(−π, π); the aim
//! point, uniform in the region. LEDs whose measured point falls outside
//! the active area (or cannot be projected) are dropped; a pose that keeps
//! fewer than [`MIN_POINTS_PER_IMAGE`] is redrawn (after 200 redraws the aim
//! is the region's centre pulled halfway to the electrical centre).

use nalgebra::Vector2;
use psdcal_model::{Model, Pose, SensorModel};
use rand::Rng;

use super::{ACTIVE_HALF_SIDE_MM, MIN_POINTS_PER_IMAGE};
use crate::poses::aimed_pose;

/// The coverage range (fraction of the active area), drawn uniformly.
pub const COVERAGE_RANGE: (f64, f64) = (0.3, 0.9);

/// The tilt range, degrees, drawn uniformly.
pub const TILT_RANGE_DEG: (f64, f64) = (5.0, 45.0);

/// Where a scenario's images are aimed: a square on the sensor, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AimRegion {
    /// Its centre, mm, sensor frame.
    pub centre: Vector2<f64>,
    /// Its half-width, mm.
    pub half_width: f64,
}

/// Draws the scenario's aim region (centre x, centre y, half-width).
pub fn draw_region<R: Rng + ?Sized>(rng: &mut R) -> AimRegion {
    let centre = Vector2::new(rng.random_range(-1.5..1.5), rng.random_range(-1.5..1.5));
    let half_width = rng.random_range(1.0..3.5);
    AimRegion { centre, half_width }
}

/// One image's pose and how it was drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WideView {
    /// `sensor_from_template`.
    pub pose: Pose,
    /// The target coverage (fraction of the active area, fronto-parallel).
    pub coverage: f64,
    /// The tilt, radians.
    pub tilt: f64,
    /// Where the template origin's ideal image is, mm.
    pub aim: Vector2<f64>,
    /// How many poses were drawn before this one was kept.
    pub redraws: usize,
}

/// Draws one image (module documentation): its view and the LEDs it keeps,
/// `(led, measured point)` noise-free, in LED order.
pub fn draw_view<R: Rng + ?Sized>(
    truth: &SensorModel,
    template: &[Vector2<f64>],
    region: &AimRegion,
    rng: &mut R,
) -> (WideView, Vec<(usize, Vector2<f64>)>) {
    let (min, max) = template.iter().fold(
        (
            Vector2::repeat(f64::INFINITY),
            Vector2::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    let extent = ((max.x - min.x) * (max.y - min.y)).sqrt();
    let side = 2.0 * ACTIVE_HALF_SIDE_MM;
    let f = truth.intrinsics.f;
    let chain = Model::standard(truth);
    let mut redraws = 0;
    loop {
        let coverage = rng.random_range(COVERAGE_RANGE.0..COVERAGE_RANGE.1);
        let z = f * extent / (coverage.sqrt() * side);
        let tilt = rng
            .random_range(TILT_RANGE_DEG.0..TILT_RANGE_DEG.1)
            .to_radians();
        let axis = rng.random_range(0.0..std::f64::consts::TAU);
        let roll = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        let h = region.half_width;
        let mut aim =
            region.centre + Vector2::new(rng.random_range(-h..h), rng.random_range(-h..h));
        if redraws >= 200 {
            aim = 0.5 * region.centre;
        }
        let pose = aimed_pose(truth, aim, z, tilt, axis, roll);
        let points = visible_points(&chain, template, &pose);
        if points.len() >= MIN_POINTS_PER_IMAGE {
            let view = WideView {
                pose,
                coverage,
                tilt,
                aim,
                redraws,
            };
            return (view, points);
        }
        redraws += 1;
        assert!(
            redraws < 10_000,
            "no pose keeps {MIN_POINTS_PER_IMAGE} LEDs"
        );
    }
}

/// The LEDs of `template` whose measured point in `pose` lies strictly
/// inside the active area, `(led, point)` in LED order.
pub fn visible_points(
    truth: &Model,
    template: &[Vector2<f64>],
    pose: &Pose,
) -> Vec<(usize, Vector2<f64>)> {
    template
        .iter()
        .enumerate()
        .filter_map(|(led, p)| {
            let m = truth.project_to_tolerance(pose, p).ok()?;
            (m.x.abs() < ACTIVE_HALF_SIDE_MM && m.y.abs() < ACTIVE_HALF_SIDE_MM).then_some((led, m))
        })
        .collect()
}
