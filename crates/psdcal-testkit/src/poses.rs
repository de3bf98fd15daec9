//! Seeded `sensor_from_template` poses whose images together cover the
//! sensor. Two draws, each kept exactly as the tests were calibrated with
//! (changing a draw changes every seeded test that uses it):
//!
//! - [`covering_poses`] (the refinement, calibration and location tests):
//!   the template centre aimed at a jittered 3 × 3 grid of sensor positions
//!   (±2.6 mm, jitter ±0.6 mm, more images cycle through it), 0.7–1.5 m
//!   away, tilted up to 30° about a random axis in the template plane, any
//!   roll; a pose is redrawn until every LED's measured point lies strictly
//!   inside ±4.4 mm.
//! - [`aimed_grid_poses`] (the linear-stage tests): the same idea with a
//!   tilt in `[0.3, 1] × max_tilt` (or none), every measured point inside
//!   ±[`HALF_SIDE_MM`], and the aim pulled towards the centre when no pose
//!   fits.

use nalgebra::{Rotation3, Unit, Vector2, Vector3};
use psdcal_model::{Model, Pose, SensorModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Half-side of the square every measured point of [`aimed_grid_poses`] must
/// fall in, mm.
pub const HALF_SIDE_MM: f64 = 4.4;

/// `n` poses of [`covering_poses`]'s draw (module documentation) that keep
/// every LED of `template` on the sensor of `truth`, drawn from `rng`.
pub fn covering_poses(
    truth: &SensorModel,
    template: &[Vector2<f64>],
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<Pose> {
    let mut out = Vec::with_capacity(n);
    let model = Model::standard(truth);
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
            model
                .project_to_tolerance(&pose, xy)
                .map(|m| m.x.abs() < 4.4 && m.y.abs() < 4.4)
                .unwrap_or(false)
        });
        if inside {
            out.push(pose);
        }
    }
    out
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
pub fn fits(model: &Model, pose: &Pose, template: &[Vector2<f64>]) -> bool {
    template
        .iter()
        .all(|p| match model.project_to_tolerance(pose, p) {
            Ok(m) => m.x.abs() <= HALF_SIDE_MM && m.y.abs() <= HALF_SIDE_MM,
            Err(_) => false,
        })
}

/// `n` poses of [`aimed_grid_poses`]'s draw (module documentation) that keep
/// `template` on the sensor, from a ChaCha8 stream seeded with `seed`. With
/// `max_tilt = 0` the poses are fronto-parallel with `rvec = 0`.
pub fn aimed_grid_poses(
    model: &SensorModel,
    template: &[Vector2<f64>],
    n: usize,
    max_tilt: f64,
    seed: u64,
) -> Vec<Pose> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    let chain = Model::standard(model);
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
                if fits(&chain, &pose, template) {
                    out.push(pose);
                    break 'aim;
                }
            }
            reach *= 0.8;
        }
    }
    out
}

/// The truth disturbed: a start for the refinement that is near but not at
/// it (f × 1.04, centre moved by (0.15, −0.2) mm, k1 × 0.8, k2 = 0, every
/// pose turned by (0.01, −0.015, 0.02) rad and moved by (8, −5, 30) mm).
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

/// `n` emitters in view of a sensor placed at `room_from_sensor`, in the
/// room frame: depth 1.5–5 m along the optical axis, `x/z` and `y/z` within
/// `±half_tan` (the surveyed and in-situ tests' draw: depth, then x, then y
/// per point, from `rng`).
pub fn points_in_view(
    room_from_sensor: &Pose,
    half_tan: f64,
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<Vector3<f64>> {
    (0..n)
        .map(|_| {
            let z = rng.random_range(1500.0..5000.0);
            let p = Vector3::new(
                rng.random_range(-half_tan..half_tan) * z,
                rng.random_range(-half_tan..half_tan) * z,
                z,
            );
            room_from_sensor.transform(&p)
        })
        .collect()
}
