//! A fixed stage's uncertainty carried into the estimated parameters
//! (docs/model.md §8.3): a PSD map held fixed at its fitted coefficients `m̂`
//! (covariance `C_m`, from its own scan) moves the calibration's estimate
//! with it. To first order, at the solution,
//!
//! ```text
//! θ̂(m̂) = θ̂(m*) + G (m̂ − m*),    G = ∂θ̂/∂m = −S_θθ⁻¹ S_θm
//! Cov θ̂ = C_θ + G C_m Gᵀ,         Cov(m̂, θ̂) = C_m Gᵀ
//! ```
//!
//! where `S` is the information of the freed parameters and the map's
//! coefficients together after eliminating the poses (the Schur complement
//! of the normal equations with the map's coefficients freed, poses
//! included), and `C_θ` the calibration's own covariance. The normal
//! equations are the unweighted ones of the fit's cost (exact for the
//! default uniform cost; with a noise model's weights `G` is the
//! unweighted fit's, a first-order approximation).

use nalgebra::DMatrix;
use psdcal_model::{Model, ParameterCovariance, Pose};

use crate::data::CalibrationData;
use crate::problem::calibration_problem::{CalibrationProblem, FitState};
use crate::refine::options::RefineOptions;
use crate::CalibError;

/// The estimate's covariance with a fixed block's carried in.
#[derive(Debug, Clone, PartialEq)]
pub struct CarriedCovariance {
    /// `C_θ + G C_m Gᵀ` over the estimated names.
    pub parameters: ParameterCovariance,
    /// `C_m Gᵀ`: rows the fixed block's names, columns the estimated names.
    pub cross: DMatrix<f64>,
    /// `G` (estimated × fixed).
    pub sensitivity: DMatrix<f64>,
}

/// Carries `fixed` (a covariance over some of `model`'s fixed parameters)
/// into `estimated` (the calibration's covariance over `options`' freed
/// parameters, in `options.free_names()` order), at the solution `model`,
/// `poses`.
pub fn carry_fixed_covariance(
    data: &CalibrationData,
    model: &Model,
    poses: &[Pose],
    options: &RefineOptions,
    estimated: &ParameterCovariance,
    fixed: &ParameterCovariance,
) -> Result<CarriedCovariance, CalibError> {
    let theta = options.free_names();
    if estimated.names() != theta.as_slice() {
        return Err(CalibError::InvalidInput {
            reason: "the covariance's names are not the freed parameters".into(),
        });
    }
    let mut joint = options.clone();
    joint
        .free_stage_parameters
        .extend(fixed.names().iter().cloned());
    let names = joint.free_names();
    let problem = CalibrationProblem::new(data, options.cost, model, &names, None)?;
    let state = FitState {
        model: model.clone(),
        poses: poses.to_vec(),
    };
    let ne = psdcal_solver::solver::normal_equations(&problem, &state, options.robust)?;
    let s = ne
        .schur_complement()
        .ok_or_else(|| CalibError::Degenerate {
            reason: "a pose block of the information is singular".into(),
        })?;
    let (nt, nm) = (theta.len(), fixed.len());
    let s_tt = s.view((0, 0), (nt, nt)).into_owned();
    let s_tm = s.view((0, nt), (nt, nm)).into_owned();
    let g = -s_tt
        .cholesky()
        .ok_or_else(|| CalibError::Degenerate {
            reason: "the freed parameters' information is singular".into(),
        })?
        .solve(&s_tm);
    let cm = fixed.matrix();
    let carried = estimated.matrix() + &g * cm * g.transpose();
    let carried = (&carried + carried.transpose()) * 0.5;
    let parameters =
        ParameterCovariance::new(theta, carried).map_err(|e| CalibError::Numerical {
            stage: "carried covariance",
            reason: e.to_string(),
        })?;
    Ok(CarriedCovariance {
        parameters,
        cross: cm * g.transpose(),
        sensitivity: g,
    })
}
