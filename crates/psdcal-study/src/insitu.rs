//! In-situ calibration trials (docs/model.md §8.4): a scene of psdcal-sim's
//! [`psdcal_sim::insitu`] calibrated by psdcal-calib's
//! [`psdcal_calib::surveyed`] from its DLT start, and the same model refined
//! from the truth (the reference: what the data allow), both judged by their
//! angle-of-arrival errors.
//!
//! *AoA error* of an estimated model `θ̂` against the truth `θ`: over a 9 × 9
//! grid of measured points on the central 90 % of the active area, the angle
//! between the rays `(a, b, 1)` of `θ̂` and of `θ` through the same point; the
//! RMS over the grid, radians. Both models' rays are in their own sensor
//! frame (the frame the calibration defines), as `aoa` would answer.
//!
//! *Predicted AoA σ*: the angle of arrival `α = (atan a, atan b)` of each
//! grid point, its Jacobian with respect to the freed parameters
//! `∂α/∂θ = diag(1/(1 + a²), 1/(1 + b²)) ∂(a, b)/∂θ` (the chain's analytic
//! ray Jacobian), and `σ_α² = tr(∂α/∂θ C ∂α/∂θᵀ)/2` per axis from the
//! calibration's covariance `C`; the RMS over the grid, radians.

use nalgebra::{DMatrix, Matrix2, Vector2, Vector3};
use psdcal_calib::surveyed::{finish_refined, refine_surveyed};
use psdcal_calib::{
    calibrate_surveyed, CalibError, ImageObservations, Observation, SurveyedCalibration,
    SurveyedData, SurveyedOptions,
};
use psdcal_model::{Model, ParameterCovariance, PsdGeometry};
use psdcal_sim::insitu::{InSituOptions, InSituScene};
use psdcal_sim::SimError;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// A scene's data as the calibration's input (the surveyed positions, not
/// the true ones).
pub fn scene_data(scene: &InSituScene) -> SurveyedData {
    SurveyedData {
        points: scene.surveyed.clone(),
        names: (1..=scene.surveyed.len()).map(|k| k.to_string()).collect(),
        images: scene
            .observations
            .iter()
            .enumerate()
            .map(|(i, seen)| ImageObservations {
                id: format!("{}", i + 1),
                points: seen
                    .iter()
                    .map(|&(led, measured)| Observation { led, measured })
                    .collect(),
            })
            .collect(),
        geometry: scene.options.geometry,
    }
}

/// The measured points the AoA is judged on.
pub fn aoa_grid(geometry: &PsdGeometry) -> Vec<Vector2<f64>> {
    let n = 9;
    let mut grid = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let u = -0.45 + 0.9 * i as f64 / (n - 1) as f64;
            let v = -0.45 + 0.9 * j as f64 / (n - 1) as f64;
            grid.push(Vector2::new(u * geometry.lx, v * geometry.ly));
        }
    }
    grid
}

/// RMS angle between the rays of `estimate` and `truth` over the grid, rad.
pub fn aoa_error_rms(estimate: &Model, truth: &Model, geometry: &PsdGeometry) -> f64 {
    let grid = aoa_grid(geometry);
    let unit = |ab: Vector2<f64>| Vector3::new(ab.x, ab.y, 1.0).normalize();
    let ss: f64 = grid
        .iter()
        .map(|m| {
            let c = unit(estimate.ray(m))
                .dot(&unit(truth.ray(m)))
                .clamp(-1.0, 1.0);
            let angle = c.acos();
            angle * angle
        })
        .sum();
    (ss / grid.len() as f64).sqrt()
}

/// The predicted AoA σ per axis (module documentation), RMS over the grid, rad.
pub fn predicted_aoa_sigma(
    model: &Model,
    covariance: &ParameterCovariance,
    geometry: &PsdGeometry,
) -> f64 {
    let names = covariance.names().to_vec();
    let c = covariance.matrix();
    let mut jac = model.jacobian_buffer();
    let grid = aoa_grid(geometry);
    let mut total = 0.0;
    for m in &grid {
        let ab = model.ray_with_jacobians(m, &mut jac);
        let d = Matrix2::new(
            1.0 / (1.0 + ab.x * ab.x),
            0.0,
            0.0,
            1.0 / (1.0 + ab.y * ab.y),
        );
        let mut j = DMatrix::<f64>::zeros(2, names.len());
        for (k, name) in names.iter().enumerate() {
            if let Some(col) = model.index(name) {
                let v = d * jac.column(col);
                j[(0, k)] = v.x;
                j[(1, k)] = v.y;
            }
        }
        total += 0.5 * (&j * c * j.transpose()).trace();
    }
    (total / grid.len() as f64).sqrt()
}

/// One trial's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct InSituTrial {
    /// The calibration from the DLT start.
    pub fit: SurveyedCalibration,
    /// Its RMS AoA error, rad.
    pub aoa_error: f64,
    /// The same model refined from the truth: its RMS AoA error, rad.
    pub aoa_error_from_truth: f64,
    /// The cost of the fit started from the truth, mm².
    pub cost_from_truth: f64,
    /// The true focal length, mm.
    pub true_f: f64,
    /// Emitters per orientation.
    pub seen: Vec<usize>,
    /// The largest angle (rad) between the estimated and the true sensor
    /// orientation over the images.
    pub pose_angle_error: f64,
    /// The largest distance (mm) between the estimated and the true sensor
    /// position in the room over the images.
    pub position_error_mm: f64,
}

/// Why a trial could not run.
#[derive(Debug)]
pub enum TrialError {
    /// The scene could not be drawn.
    Scene(SimError),
    /// The calibration failed.
    Calibration(CalibError),
}

/// Draws the scene of `seed` (ChaCha8) and calibrates it; `wide`: the scene's
/// options are drawn by [`InSituOptions::wide`] from the same generator.
pub fn run_trial(
    options: &InSituOptions,
    wide: bool,
    seed: u64,
) -> Result<InSituTrial, TrialError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let options = if wide {
        InSituOptions::wide(&mut rng)
    } else {
        options.clone()
    };
    let scene = InSituScene::draw(&options, &mut rng).map_err(TrialError::Scene)?;
    let data = scene_data(&scene);
    let calib = SurveyedOptions {
        survey_sigma_mm: options.survey_sigma_mm,
        ..SurveyedOptions::default()
    };
    let fit = calibrate_surveyed(&data, &calib).map_err(TrialError::Calibration)?;
    let truth = Model::standard(&options.truth);
    let from_truth = refine_surveyed(&data, truth.clone(), &scene.sensor_from_room(), &calib)
        .and_then(|r| finish_refined(&data, &calib, r))
        .map_err(TrialError::Calibration)?;
    let geometry = &options.geometry;
    let mut pose_angle_error: f64 = 0.0;
    let mut position_error_mm: f64 = 0.0;
    for (est, true_pose) in fit.poses.iter().zip(&scene.room_from_sensor) {
        let room_from_sensor = est.inverse();
        let dr = room_from_sensor.rotation().transpose() * true_pose.rotation();
        let angle = ((dr.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos();
        pose_angle_error = pose_angle_error.max(angle);
        position_error_mm = position_error_mm.max((room_from_sensor.t - true_pose.t).norm());
    }
    Ok(InSituTrial {
        aoa_error: aoa_error_rms(&fit.model, &truth, geometry),
        aoa_error_from_truth: aoa_error_rms(&from_truth.model, &truth, geometry),
        cost_from_truth: from_truth.cost,
        true_f: options.truth.intrinsics.f,
        seen: scene.observations.iter().map(Vec::len).collect(),
        pose_angle_error,
        position_error_mm,
        fit,
    })
}
