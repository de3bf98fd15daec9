//! What a calibration notices about itself (docs/model.md §4.7,
//! docs/formats.md "Diagnostic codes"): psdcal-model's
//! [`Diagnostic`]s, computed once from the finished fit.
//!
//! **Residual structure** (`model_misfit`, `gain_imbalance_suspected`): the
//! image-plane residuals at the solution are tested for a smooth field shared
//! by the images that the model does not contain (a cubic field and the gain
//! field, by F-tests at `p = 1e-6`), and against a known point noise by a χ²
//! test ([`crate::residual_structure`]).
//!
//! **Local minima** (`local_minimum_suspected`, from the global search over
//! `l1`, [`GlobalReport`]; a fit without it says nothing): a warning when
//! another minimum is within `Δχ² < 9` of the winner
//! ([`GlobalReport::competing`]), an info when several starts ran and only
//! one reached the winner.
//!
//! **Uncertainty** (`uncertainty_unreliable`): the covariance `σ² S⁻¹` is a
//! quadratic model of the cost. (a) The condition number of the unit-diagonal
//! information `S` above [`MAX_CONDITION`] (1e10: some combination of the
//! parameters has a standard deviation 1e5 times that of the best-determined
//! one, in units of each parameter's own spread — the covariance then rests
//! on the last digits of `JᵀJ`). The curvature of the cost at ±3σ of every
//! freed parameter is [`crate::linearity`]'s verdict, carried by the result
//! (`CalibrationResult::linearity`) but not raised as this code yet: on data
//! with channel noise (points of unequal noise) it also flags clean fits.

use nalgebra::{DMatrix, SymmetricEigen};
use psdcal_model::{Diagnostic, DiagnosticCode};
use psdcal_solver::normal_equations::inverse_scaled;

use crate::data::CalibrationData;
pub use crate::diagnose::residual_structure::{
    diagnose_residuals, DiagnosticOptions, DiagnosticReport, FieldTest, ImagePlaneFit, GAIN_SHARE,
    MIN_EXPLAINED, MISFIT_RATIO, RANK_CUTOFF, SIGNIFICANCE_Z,
};
use crate::problem::calibration_problem::{CalibrationProblem, FitState};
use crate::refine::global::GlobalReport;
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::uncertainty::covariance::Covariance;
use psdcal_model::CostKind;

/// Condition number of the unit-diagonal information matrix above which the
/// covariance is unreliable.
pub const MAX_CONDITION: f64 = 1e10;
/// What the user is told to do about a suspected gain imbalance, for a
/// planar fit (whose gains can be fitted from signals.csv).
pub const PLANAR_GAIN_ADVICE: &str = "fit the gains from the electrode signals (--signals \
     signals.csv --fit f,cx,cy,k1,k2,gains), or measure them (psdcal gains) and give them with --gains";

/// Diagnoses a finished fit (module documentation): `refined` with the
/// options it was refined with, its covariance and the global search's
/// report when there was one.
pub fn diagnose(
    data: &CalibrationData,
    refined: &Refined,
    options: &RefineOptions,
    covariance: &Covariance,
    global: Option<&GlobalReport>,
    extra: &DiagnosticOptions,
) -> DiagnosticReport {
    let mut report = diagnose_structure(data, refined, options, extra);
    diagnose_uncertainty(&mut report, covariance, global);
    report
}

/// The residual-structure part of [`diagnose`] (`model_misfit`,
/// `gain_imbalance_suspected`), which needs no covariance: it can run
/// while the covariance is computed. The fit's problem is taken in the
/// image plane whatever cost was minimised (module documentation).
pub fn diagnose_structure(
    data: &CalibrationData,
    refined: &Refined,
    options: &RefineOptions,
    extra: &DiagnosticOptions,
) -> DiagnosticReport {
    let free = options.free_names();
    let Ok(problem) = CalibrationProblem::new(data, CostKind::Image, &refined.model, &free, None)
    else {
        return DiagnosticReport::default();
    };
    let state = FitState {
        model: refined.model.clone(),
        poses: refined.poses.clone(),
    };
    let gains_fitted = options.fit_gains && refined.model.gains_stage().is_some();
    diagnose_residuals(&problem, &state, !gains_fitted, extra, PLANAR_GAIN_ADVICE)
}

/// The rest of [`diagnose`] on `report` from [`diagnose_structure`]:
/// `local_minimum_suspected` (from the global search, when there was one)
/// and `uncertainty_unreliable` (from the covariance).
pub fn diagnose_uncertainty(
    report: &mut DiagnosticReport,
    covariance: &Covariance,
    global: Option<&GlobalReport>,
) {
    if let Some(g) = global {
        local_minima(g, covariance.sigma2, report);
    }
    diagnose_conditioning(covariance.matrix(), report);
}

/// The local-minimum diagnostics of the global search.
fn local_minima(global: &GlobalReport, sigma2: f64, report: &mut DiagnosticReport) {
    if global.competing(sigma2) {
        let (best, next) = (&global.minima[0], &global.minima[1]);
        let d = global.runner_up_delta_chi2(sigma2).unwrap_or(0.0);
        report.diagnostics.push(Diagnostic::warning(
            DiagnosticCode::LocalMinimumSuspected,
            format!(
                "another minimum of the cost over l1 (l1 = {:.4e}, cost {:.4e}) is within Δχ² = {d:.2} \
                 of the one kept (l1 = {:.4e}, cost {:.4e}): the data barely prefer it; add images \
                 or measure l1 separately",
                next.l1, next.cost, best.l1, best.cost
            ),
        ));
    } else if let Some(evidence) = missed_minimum_evidence(global) {
        report.diagnostics.push(Diagnostic::info(
            DiagnosticCode::LocalMinimumSuspected,
            format!("{evidence}: a lower minimum of the cost over l1 may have been missed"),
        ));
    }
}

/// What in the global search's own record could hide a lower minimum: a
/// winner at the edge of the `l1` grid (the cost may fall further past it),
/// or grid points where no refinement succeeded (a basin there was never
/// looked at). Between grid points that all succeeded, the final check
/// guarantees no point of the profile below the winner
/// ([`crate::refine::global`]); how many restarts reached the winner is no
/// evidence (restarts from the profile's other minima end in their own
/// basins by design).
fn missed_minimum_evidence(global: &GlobalReport) -> Option<String> {
    let winner = global.minima.first()?;
    let grid: Vec<f64> = global.profile.iter().map(|(l1, _)| *l1).collect();
    let (lo, hi) = (grid.first()?, grid.last()?);
    let step = (hi - lo) / (grid.len().max(2) - 1) as f64;
    if winner.l1 <= lo + 0.5 * step || winner.l1 >= hi - 0.5 * step {
        return Some(format!(
            "the l1 kept ({:.4e} mm⁻²) is at the edge of the searched range {lo:.1e} to {hi:.1e} mm⁻²",
            winner.l1
        ));
    }
    let failed: Vec<String> = global
        .profile
        .iter()
        .filter(|(_, cost)| cost.is_none())
        .map(|(l1, _)| format!("{l1:.1e}"))
        .collect();
    (!failed.is_empty()).then(|| {
        format!(
            "no refinement succeeded with l1 held at {} mm⁻²",
            failed.join(", ")
        )
    })
}

/// The conditioning part of `uncertainty_unreliable` (module
/// documentation) for any fit's covariance of its freed parameters.
pub fn diagnose_conditioning(sigma: &DMatrix<f64>, report: &mut DiagnosticReport) {
    let p = sigma.nrows();
    if p == 0 {
        return;
    }
    let Some(information) = inverse_scaled(sigma) else {
        report.diagnostics.push(Diagnostic::warning(
            DiagnosticCode::UncertaintyUnreliable,
            "the covariance is singular: some parameter combination is not determined",
        ));
        return;
    };
    let d: Vec<f64> = (0..p).map(|k| 1.0 / information[(k, k)].sqrt()).collect();
    let scaled = DMatrix::from_fn(p, p, |i, j| information[(i, j)] * d[i] * d[j]);
    let eig = SymmetricEigen::new(scaled);
    let (lo, hi) = eig
        .eigenvalues
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &l| {
            (lo.min(l), hi.max(l))
        });
    let condition = if lo > 0.0 { hi / lo } else { f64::INFINITY };
    report.condition = Some(condition);
    if condition > MAX_CONDITION {
        report.diagnostics.push(Diagnostic::warning(
            DiagnosticCode::UncertaintyUnreliable,
            format!(
                "the information matrix is nearly singular (condition number {condition:.1e} after \
                 scaling): the reported σ and correlations rest on rounding; fix a parameter or \
                 vary the template poses more"
            ),
        ));
    }
    // The curvature at ±3σ is the linearity check's ([`crate::linearity`]).
}
