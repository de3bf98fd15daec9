//! Shared helpers of psdcal-locate's tests: models, rigs, synthetic
//! calibration scenarios (the idea of psdcal-calib's `tests/support`: a
//! 14-LED template, poses 0.7–1.5 m away tilted up to 30°, Gaussian point
//! noise) and finite differences. The template, the pose draw and the
//! observations come from `psdcal-testkit`.
#![allow(dead_code)]

use nalgebra::{Vector2, Vector3};
use psdcal_calib::CalibrationData;
use psdcal_locate::{measured_from_ray, CalibratedSensor, Rig, RigSensor};
use psdcal_model::{Pose, PsdGeometry, SensorModel};
use psdcal_testkit::PointKind;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::Normal;

/// The paper's two lenses, and lens 2 with every model term non-zero.
pub fn models() -> Vec<(&'static str, SensorModel)> {
    let mut full = SensorModel::paper_lens2();
    full.intrinsics.skew = 0.01;
    full.distortion.k3 = 2e-7;
    full.distortion.p1 = 3e-4;
    full.distortion.p2 = -2e-4;
    full.distortion.l1 = SensorModel::PAPER_L1;
    full.distortion.l2 = 2e-6;
    let mut lens1_psd = SensorModel::paper_lens1();
    lens1_psd.distortion.l1 = SensorModel::PAPER_L1;
    vec![
        ("lens1", SensorModel::paper_lens1()),
        ("lens2", SensorModel::paper_lens2()),
        ("lens1+psd", lens1_psd),
        ("lens2 full", full),
    ]
}

/// Measured points over the active area (a 5 × 5 grid to ±4 mm).
pub fn sensor_points() -> Vec<Vector2<f64>> {
    let mut out = Vec::new();
    for iy in 0..5 {
        for ix in 0..5 {
            out.push(Vector2::new(-4.0 + 2.0 * ix as f64, -4.0 + 2.0 * iy as f64));
        }
    }
    out
}

/// The measured point of a sensor-frame point in front of the sensor.
pub fn measure(model: &SensorModel, p_sensor: &Vector3<f64>) -> Vector2<f64> {
    measured_from_ray(
        &psdcal_model::Model::standard(model),
        &Vector2::new(p_sensor.x / p_sensor.z, p_sensor.y / p_sensor.z),
    )
    .expect("the point is in the model's valid region")
}

/// A pose looking from `origin` towards `target` (sensor z axis along the
/// line of sight), world frame.
pub fn looking_at(origin: Vector3<f64>, target: Vector3<f64>, roll: f64) -> Pose {
    let z = (target - origin).normalize();
    let helper = if z.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let x0 = helper.cross(&z).normalize();
    let y0 = z.cross(&x0);
    let (s, c) = roll.sin_cos();
    let x = x0 * c + y0 * s;
    let y = z.cross(&x);
    let r = nalgebra::Matrix3::from_columns(&[x, y, z]);
    Pose::from_rotation(&r, origin)
}

/// Three sensors on a 3 m × 2 m ceiling frame looking at a point 2.5 m
/// below its centre, world frame in mm.
pub fn three_sensor_rig(model: SensorModel) -> Rig {
    let target = Vector3::new(0.0, 0.0, 0.0);
    let sensors = [
        Vector3::new(-1500.0, -1000.0, 2500.0),
        Vector3::new(1500.0, -1000.0, 2500.0),
        Vector3::new(0.0, 1200.0, 2600.0),
    ]
    .iter()
    .enumerate()
    .map(|(k, origin)| RigSensor {
        id: format!("s{}", k + 1),
        sensor: CalibratedSensor::new(model, PsdGeometry::default()),
        world_from_sensor: looking_at(*origin, target, 0.3 * k as f64),
    })
    .collect();
    Rig::new(sensors).expect("valid rig")
}

/// Relative error of an analytic derivative against a finite difference,
/// scaled by `scale` (the size of the derivative block).
pub fn rel(analytic: f64, numeric: f64, scale: f64) -> f64 {
    (analytic - numeric).abs() / scale.max(1e-300)
}

// --- Calibration scenarios -------------------------------------------------

/// The template: `scatter14`, 14 LEDs (mm), no three collinear.
pub fn template() -> Vec<Vector2<f64>> {
    psdcal_testkit::scatter14()
}

/// Random poses aimed at a jittered 3 × 3 grid over the sensor, 0.7–1.5 m
/// away, tilted up to 30° about an axis in the template plane, any roll;
/// redrawn until every LED falls inside ±4.4 mm.
pub fn poses(truth: &SensorModel, n: usize, rng: &mut ChaCha8Rng) -> Vec<Pose> {
    psdcal_testkit::covering_poses(truth, &template(), n, rng)
}

/// The poses of a scenario, from `seed`.
pub fn scenario_poses(truth: &SensorModel, n: usize, seed: u64) -> Vec<Pose> {
    poses(truth, n, &mut ChaCha8Rng::seed_from_u64(seed))
}

/// Every LED measured in every pose, with Gaussian noise of `sigma_mm` per
/// coordinate drawn from `rng`.
pub fn observe(
    truth: &SensorModel,
    poses: &[Pose],
    sigma_mm: f64,
    rng: &mut ChaCha8Rng,
) -> CalibrationData {
    let template = template();
    let noise = Normal::new(0.0, sigma_mm).expect("valid sigma");
    let mut points = psdcal_testkit::image_points(truth, &template, poses, PointKind::Measured);
    psdcal_testkit::add_noise(&mut points, &noise, rng);
    CalibrationData::from_points(&template, &[], points, PsdGeometry::default())
}
