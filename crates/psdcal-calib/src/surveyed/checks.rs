//! What a fit from surveyed 3-D points notices about itself (docs/model.md
//! §8.4, "Diagnostics"): the same tests as a planar fit, on the surveyed
//! fit's own problem.
//!
//! - **Residual structure** (`model_misfit`, `gain_imbalance_suspected`):
//!   [`crate::diagnostics::diagnose_residuals`] on [`SurveyedProblem`], whose
//!   residuals are already the image-plane errors `project(θ, pose_i, P_j) −
//!   m_ij`: the cubic and gain fields appended to its normal equations, the
//!   same F-tests and thresholds. The 3-D fit has no gains stage, so the gain
//!   field is always tested. No χ² test against a known point noise: the
//!   residual also carries the survey's share, which only an assumed survey σ
//!   describes.
//! - **Conditioning** (`uncertainty_unreliable`): the condition number of the
//!   unit-diagonal information of the reported covariance (survey noise
//!   included), [`crate::diagnostics::diagnose_conditioning`].
//! - **Linearity**: [`crate::linearity::check_quadratic`] at `θ̂ ± 3σ_k`, `σ_k`
//!   the reported standard deviation (survey noise included), along the
//!   direction `S⁻¹ e_k` of the fit's own normal equations, where the
//!   quadratic model predicts the cost to rise by `9 σ_k² / S⁻¹_kk`. As for a
//!   planar fit, the verdict is carried by the result, not raised as a
//!   diagnostic.
//!
//! No `local_minimum_suspected`: the 3-D fit has no global search over `l1`
//! (its competing starts keep the lowest converged cost).

use psdcal_model::{Model, ParameterCovariance, PsdGeometry};
use psdcal_solver::solver;

use crate::diagnose::diagnostics::diagnose_conditioning;
use crate::diagnose::residual_structure::{
    diagnose_residuals, DiagnosticOptions, DiagnosticReport, ImagePlaneFit,
};
use crate::surveyed::input::{SurveyedData, SurveyedOptions};
use crate::surveyed::problem::{SurveyedProblem, SurveyedState};
use crate::uncertainty::linearity::{
    check_quadratic, FitAtSolution, LinearityCheck, UncertaintyVerdict,
};
use crate::CalibError;

/// What `gain_imbalance_suspected` tells the user of a 3-D fit to do.
pub const SURVEYED_GAIN_ADVICE: &str = "the 3-D fit does not estimate gains: measure them \
     (psdcal gains) and give them with --gains together with --signals";

impl ImagePlaneFit for SurveyedProblem<'_> {
    fn geometry(&self) -> &PsdGeometry {
        &self.data().geometry
    }

    fn freed_columns(&self) -> Vec<usize> {
        self.columns().to_vec()
    }

    fn image_sizes(&self) -> Vec<usize> {
        self.data().images.iter().map(|i| i.points.len()).collect()
    }

    fn measured_point(
        &self,
        _: &Model,
        i: usize,
        k: usize,
    ) -> Result<nalgebra::Vector2<f64>, CalibError> {
        Ok(self.data().images[i].points[k].measured)
    }
}

/// The diagnostics and the linearity check of a surveyed fit.
#[derive(Debug, Clone, PartialEq)]
pub struct SurveyedChecks {
    /// The diagnostics with the statistics behind them.
    pub report: DiagnosticReport,
    /// The cost at ±3σ of each freed parameter.
    pub linearity: LinearityCheck,
}

/// Runs the checks (module documentation) at the solution `state` with the
/// reported `covariance` of the freed parameters.
pub fn check_surveyed(
    data: &SurveyedData,
    options: &SurveyedOptions,
    state: &SurveyedState,
    covariance: &ParameterCovariance,
) -> Result<SurveyedChecks, CalibError> {
    let problem = SurveyedProblem::new(data, &state.model, &options.free)?;
    let mut report = diagnose_residuals(
        &problem,
        state,
        true,
        &DiagnosticOptions::default(),
        SURVEYED_GAIN_ADVICE,
    );
    diagnose_conditioning(covariance.matrix(), &mut report);
    let names: Vec<String> = options.free.iter().map(|p| p.name().to_string()).collect();
    let reported: Vec<f64> = names
        .iter()
        .map(|n| covariance.std(n).unwrap_or(f64::NAN))
        .collect();
    let linearity = solver::normal_equations(&problem, state, None)
        .and_then(|ne| {
            let fit = FitAtSolution {
                problem: &problem,
                state,
                ne: &ne,
                names: &names,
                observations: 2 * data.images.iter().map(|i| i.points.len()).sum::<usize>(),
                robust: None,
            };
            check_quadratic(&fit, Some(&reported))
        })
        .unwrap_or_else(|e| LinearityCheck {
            parameters: Vec::new(),
            profile: Vec::new(),
            verdict: UncertaintyVerdict::Unreliable {
                reason: format!("the cost could not be evaluated around the solution: {e}"),
            },
        });
    Ok(SurveyedChecks { report, linearity })
}
