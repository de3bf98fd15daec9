//! What one template pose tells the calibration (docs/model.md §8.6):
//! the pose's share of the normal equations of the estimator `calibrate`
//! runs, at the nominal model, with the pose itself eliminated.
//!
//! For every LED `j` of a pose, with `A_j = ∂r_j/∂θ` (2 × p, the freed
//! parameters), `P_j = ∂r_j/∂pose` (2 × 6) and `B_j = ∂r_j/∂m_j` (how the
//! measured point's noise enters the residual):
//!
//! ```text
//! U = Σ A_jᵀA_j,  W = Σ A_jᵀP_j,  V = Σ P_jᵀP_j
//! S_i = U − W V⁻¹ Wᵀ                      (the pose's Schur complement)
//! Ã_j = A_j − P_j V⁻¹ Wᵀ
//! M_i = Σ Ã_jᵀ (B_j Σ_j B_jᵀ) Ã_j          (the noise it carries)
//! ```
//!
//! `Σ_j` is the covariance of the measured point: per channel an amplitude
//! noise of standard deviation `ρ V_k` (the same SNR on every channel, `ρ`
//! the relative amplitude noise of the signal chain) propagated through the
//! impact-point formula ([`crate::weighting::point_covariance`]). The
//! unweighted least-squares estimate over a set of poses then has the
//! covariance `S⁻¹ M S⁻¹` with `S = Σ S_i`, `M = Σ M_i` — the sandwich of
//! [`mod@crate::covariance`] with the point noise known instead of estimated.
//! For the image-plane cost `B_j = −I` and the same formula holds.
//!
//! **Gains.** When the model owns a gains stage (the gains freed, as
//! `calibrate --fit …,gains` frees `g_x2, g_y1, g_y2` with `g_x1 = 1`),
//! each point is the impact point of the LED's electrode amplitudes through
//! the gains, `m = P(V / g)` (docs/model.md §1), and `A_j` gains the columns
//! `B_j ∂m/∂g` (the refinement's own linearisation,
//! [`CalibrationProblem`]). The amplitudes are the simulator's: the
//! bilinear shares of the LED's noise-free measured point, times the
//! nominal gains, `V_k = g_k I0 s_k(m)` ([`nominal_amplitudes`]). Their
//! total `I0` (the LED's brightness, the amplifier's gain) cancels: `P` is
//! homogeneous of degree 0 in `V`, so `∂m/∂g` does not depend on it, and at
//! one SNR on every channel the noise is relative, `σ_k = ρ V_k`, so `Σ_j`
//! does not either (dividing by the gains keeps it relative).

use nalgebra::{DMatrix, Matrix2, SMatrix};
use psdcal_model::psd::electrode_currents;
use psdcal_model::{Amplitudes, CostKind, Model, Pose, PsdGeometry};

use crate::data::CalibrationData;
use crate::problem::calibration_problem::{CalibrationProblem, FitState};
use crate::problem::weighting::{point_covariance, NoiseModel};
use crate::CalibError;

/// What the planner knows of the sensor and the template.
#[derive(Debug, Clone)]
pub struct PlanSetup {
    /// The nominal model (the calibration expected).
    pub model: Model,
    /// The template's LEDs `(X, Y)`, mm.
    pub template: Vec<nalgebra::Vector2<f64>>,
    /// The active area.
    pub geometry: PsdGeometry,
    /// The freed parameters, by name (the calibration's `--fit`).
    pub free: Vec<String>,
    /// The cost `calibrate` minimises.
    pub cost: CostKind,
    /// `ρ`: the standard deviation of a channel's amplitude estimate per unit
    /// of amplitude (from the SNR through the signal chain).
    pub relative_noise: f64,
}

/// One pose's share of the normal equations (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct PoseInformation {
    /// `S_i` (p × p).
    pub schur: DMatrix<f64>,
    /// `M_i` (p × p).
    pub noise: DMatrix<f64>,
}

/// The measured points of every LED of `setup`'s template in `pose` through
/// the nominal model.
pub fn pose_points(
    setup: &PlanSetup,
    pose: &Pose,
) -> Result<Vec<nalgebra::Vector2<f64>>, CalibError> {
    setup
        .template
        .iter()
        .map(|xy| {
            setup
                .model
                .project(pose, xy)
                .map_err(|e| CalibError::InvalidInput {
                    reason: format!("a planned pose cannot be projected: {e}"),
                })
        })
        .collect()
}

/// The electrode amplitudes behind the measured point `m` through `model`'s
/// gains (module documentation: `V_k = g_k s_k(m)`, unit total current);
/// `None` when the model has no gains stage.
pub fn nominal_amplitudes(model: &Model, m: &nalgebra::Vector2<f64>) -> Option<Amplitudes> {
    let (stage, gains) = (model.gains_stage()?, model.gains()?);
    Some(electrode_currents(&stage.geometry, m, 1.0).apply_gains(&gains))
}

/// The planner's data set of one pose: every LED at its noise-free measured
/// point, with the amplitudes behind it when the model owns the gains.
pub fn pose_data(setup: &PlanSetup, pose: &Pose) -> Result<CalibrationData, CalibError> {
    let points = pose_points(setup, pose)?;
    let amplitudes: Option<Vec<Amplitudes>> = points
        .iter()
        .map(|m| nominal_amplitudes(&setup.model, m))
        .collect();
    let mut data = CalibrationData::from_points(&setup.template, &[], vec![points], setup.geometry);
    data.amplitudes = amplitudes.map(|a| vec![a]);
    Ok(data)
}

/// One LED's linearisation (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct PointJacobians {
    /// `A_j = ∂r_j/∂θ` (2 × p, the freed parameters, gains included).
    pub wrt_free: DMatrix<f64>,
    /// `P_j = ∂r_j/∂pose` (2 × 6).
    pub wrt_pose: SMatrix<f64, 2, 6>,
    /// `B_j Σ_j B_jᵀ`: the point noise in the residual (2 × 2).
    pub noise: Matrix2<f64>,
}

/// `A_j`, `P_j` and `B_j Σ_j B_jᵀ` of every LED of `setup`'s template in
/// `pose`, at the nominal model.
pub fn point_jacobians(setup: &PlanSetup, pose: &Pose) -> Result<Vec<PointJacobians>, CalibError> {
    let data = pose_data(setup, pose)?;
    let problem = CalibrationProblem::new(&data, setup.cost, &setup.model, &setup.free, None)?;
    let state = FitState {
        model: setup.model.clone(),
        poses: vec![*pose],
    };
    let p = setup.free.len();
    let rotation = pose.rotation_jacobian();
    let mut jac = setup.model.jacobian_buffer();
    let mut a = vec![0.0; 2 * p];
    data.images[0]
        .points
        .iter()
        .enumerate()
        .map(|(k, obs)| {
            let (_, wrt_pose, b) = problem
                .linearize(&state, 0, k, &rotation, &mut jac, &mut a)
                .map_err(|e| {
                    crate::problem::calibration_problem::point_error(&data, 0, obs.led, e)
                })?;
            Ok(PointJacobians {
                wrt_free: DMatrix::from_column_slice(2, p, &a),
                wrt_pose,
                noise: b * measured_covariance(setup, &obs.measured) * b.transpose(),
            })
        })
        .collect()
}

/// The covariance `Σ` of a measured point at `point` (module documentation).
pub fn measured_covariance(setup: &PlanSetup, point: &nalgebra::Vector2<f64>) -> Matrix2<f64> {
    let rho2 = setup.relative_noise * setup.relative_noise;
    point_covariance(NoiseModel::ChannelSnr, &setup.geometry, point, None) * rho2
}

/// `S_i` and `M_i` of one pose (module documentation).
pub fn pose_information(setup: &PlanSetup, pose: &Pose) -> Result<PoseInformation, CalibError> {
    let terms = point_jacobians(setup, pose)?;
    let p = setup.free.len();
    let (mut u, mut w, mut v) = (
        DMatrix::zeros(p, p),
        DMatrix::zeros(p, 6),
        SMatrix::<f64, 6, 6>::zeros(),
    );
    for t in &terms {
        let p_mat = DMatrix::from_column_slice(2, 6, t.wrt_pose.as_slice());
        u += t.wrt_free.transpose() * &t.wrt_free;
        w += t.wrt_free.transpose() * &p_mat;
        v += t.wrt_pose.transpose() * t.wrt_pose;
    }
    let v_inv = v.cholesky().ok_or_else(|| CalibError::Degenerate {
        reason: "a planned pose is not determined by its points".into(),
    })?;
    let v_inv = DMatrix::from_column_slice(6, 6, v_inv.inverse().as_slice());
    let wvt = &v_inv * w.transpose(); // V⁻¹ Wᵀ (6 × p)
    let schur = &u - &w * &wvt;
    let mut noise = DMatrix::zeros(p, p);
    for t in &terms {
        let p_mat = DMatrix::from_column_slice(2, 6, t.wrt_pose.as_slice());
        let a_tilde = &t.wrt_free - p_mat * &wvt;
        let n = DMatrix::from_column_slice(2, 2, t.noise.as_slice());
        noise += a_tilde.transpose() * n * &a_tilde;
    }
    Ok(PoseInformation {
        schur: (&schur + schur.transpose()) * 0.5,
        noise: (&noise + noise.transpose()) * 0.5,
    })
}

/// The covariance `S⁻¹ M S⁻¹` of the freed parameters from summed
/// information; `None` when `S` is singular (the poses do not determine
/// the parameters).
pub fn parameter_covariance(schur: &DMatrix<f64>, noise: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let s_inv = schur.clone().cholesky()?.inverse();
    let c = &s_inv * noise * &s_inv;
    Some((&c + c.transpose()) * 0.5)
}
