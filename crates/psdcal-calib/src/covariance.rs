//! Uncertainty of a calibration (docs/model.md §4.6): the covariance
//! `σ² (JᵀJ)⁻¹` of the estimated parameters at the solution, with
//! `σ² = cost / (2·points − parameters)` (`parameters` counts the freed
//! sensor parameters and 6 per pose). For a noise-weighted fit
//! ([`crate::weighting`]) `J` and `cost` are the whitened ones, so `σ²` is
//! the variance of a unit-weight coordinate and `σ² (JᵀJ)⁻¹` the
//! generalised-least-squares covariance.
//!
//! `(JᵀJ)⁻¹` is never formed whole: the sensor-parameter block is the inverse
//! of the Schur complement `S⁻¹`, and each pose's 6 × 6 block is
//! `V_i⁻¹ + V_i⁻¹ W_iᵀ S⁻¹ W_i V_i⁻¹` ([`psdcal_solver::normal_equations`]).
//!
//! Identifiability: a parameter whose information is (nearly) explained by
//! the others has a huge variance inflation `S⁻¹_kk · S_kk`; such parameters,
//! and pairs whose correlation exceeds 0.98 in magnitude (p1/p2 with cx/cy,
//! k1 with l1 when the centres nearly coincide), are reported as warnings.

use nalgebra::Matrix6;
use psdcal_model::ParameterCovariance;

use crate::data::CalibrationData;
use crate::refine::{CalibrationProblem, FitState, RefineOptions, Refined};
use crate::CalibError;
use psdcal_solver::solver;

use psdcal_model::stages::gains::GAIN_NAMES;

/// Correlation magnitude above which a pair of parameters is flagged.
pub const CORRELATION_WARNING: f64 = 0.98;
/// Variance inflation above which a parameter is flagged as poorly determined.
pub const INFLATION_WARNING: f64 = 1e4;

/// The covariance of a calibration's estimate: psdcal-model's
/// [`ParameterCovariance`] of the freed parameters (dereferenced to, for
/// `std`, `correlation`, `names`, …) with what only a fit has.
#[derive(Debug, Clone, PartialEq)]
pub struct Covariance {
    /// The freed parameters, in the order of [`RefineOptions::free_names`]
    /// (standard ones, gains, other stages'), and their covariance σ² S⁻¹
    /// in their units squared.
    pub parameters: ParameterCovariance,
    /// Per image, the 6 × 6 covariance of `(rvec, t)`.
    pub pose_blocks: Vec<Matrix6<f64>>,
    /// The residual variance σ² per coordinate (cost units: mm²).
    pub sigma2: f64,
    /// Degrees of freedom `2·points − parameters`.
    pub dof: usize,
    /// Identifiability warnings (empty when the data pin everything down).
    pub warnings: Vec<String>,
}

impl std::ops::Deref for Covariance {
    type Target = ParameterCovariance;
    fn deref(&self) -> &ParameterCovariance {
        &self.parameters
    }
}

impl Covariance {
    /// Standard deviations of the relative gains `(g_x2, g_y1, g_y2)`, when
    /// they were estimated.
    pub fn gain_std(&self) -> Option<[f64; 3]> {
        let sd = GAIN_NAMES.map(|n| self.std(n));
        sd.iter()
            .all(Option::is_some)
            .then(|| sd.map(|s| s.unwrap_or(0.0)))
    }
}

/// The covariance at a refinement's solution (its model, poses, cost and
/// point weights) for the cost and freed parameters of `options`.
pub fn covariance(
    data: &CalibrationData,
    refined: &Refined,
    options: &RefineOptions,
) -> Result<Covariance, CalibError> {
    let names = options.free_names();
    let problem = CalibrationProblem::new(
        data,
        options.cost,
        &refined.model,
        &names,
        refined.weights.as_ref(),
    )?;
    let state = FitState {
        model: refined.model.clone(),
        poses: refined.poses.clone(),
    };
    let ne = solver::normal_equations(&problem, &state, options.robust)?;
    let (columns, poses, cost) = (problem.columns(), &refined.poses, refined.cost);
    let parameters = columns.len() + 6 * poses.len();
    let observations = 2 * data.point_count();
    if observations <= parameters {
        return Err(CalibError::Degenerate {
            reason: format!(
                "{observations} coordinates cannot determine {parameters} parameters; add images or LEDs"
            ),
        });
    }
    let dof = observations - parameters;
    let sigma2 = cost / dof as f64;
    let (s_inv, pose_inv) = ne.inverse_blocks().ok_or_else(|| CalibError::Degenerate {
        reason: "the information matrix is singular: some freed parameter is not determined by the data \
                 (fix it, or add images that vary the template pose)"
            .into(),
    })?;
    let mut warnings = Vec::new();
    if let Some(s) = ne.schur_complement() {
        for (k, p) in names.iter().enumerate() {
            let inflation = s_inv[(k, k)] * s[(k, k)];
            if inflation > INFLATION_WARNING {
                warnings.push(format!(
                    "{p} is poorly determined by these images (variance inflated {inflation:.1e}× by correlation \
                     with the other parameters); consider fixing it"
                ));
            }
        }
    }
    // S⁻¹ is symmetric up to rounding: store it exactly symmetric.
    let matrix = s_inv * sigma2;
    let matrix = (&matrix + matrix.transpose()) * 0.5;
    let estimated =
        ParameterCovariance::new(names.clone(), matrix).map_err(|e| CalibError::Numerical {
            stage: "covariance",
            reason: e.to_string(),
        })?;
    let corr = estimated.correlation();
    for i in 0..names.len() {
        for j in (i + 1)..names.len() {
            if corr[(i, j)].abs() > CORRELATION_WARNING {
                warnings.push(format!(
                    "{} and {} are strongly correlated ({:+.3}): the data barely separate them",
                    names[i],
                    names[j],
                    corr[(i, j)]
                ));
            }
        }
    }
    let cov = Covariance {
        parameters: estimated,
        pose_blocks: pose_inv.into_iter().map(|b| b * sigma2).collect(),
        sigma2,
        dof,
        warnings,
    };
    Ok(cov)
}
