//! Can the linear covariance be trusted? (docs/model.md §4.6, "When the
//! linearisation fails"; calibration.json's `uncertainty_unreliable`.)
//!
//! The covariance rests on the cost being quadratic over the region the
//! estimate wanders in. The check walks, for each freed parameter `k`, to
//! `θ̂ ± 3σ_k` along the direction the quadratic model says the other
//! parameters and the poses follow (`d = c · H⁻¹ e_k`: the sensor part
//! `S⁻¹ e_k`, pose `i`'s part `−V_i⁻¹ W_iᵀ S⁻¹ e_k`, scaled so that
//! `d_k = 3 σ_lin,k`, with `σ_lin² = s² S⁻¹_kk`, `s² = cost / dof`). Along
//! it the quadratic model predicts the cost to rise by exactly
//! `dᵀ H d = 9 s²`. The ratio `ρ = (cost(θ̂ + d) − cost(θ̂)) / (9 s²)` is 1
//! for a linear model; a departure beyond [`LINEARITY_TOLERANCE`] on either
//! side means the cost is not quadratic at 3σ, and σ is not a 3σ-interval
//! (the estimate's spread, its bias and the σ reported at each estimate all
//! depend on where noise puts it). Twenty cost evaluations, no refit.
//!
//! A walk that finds the cost quadratic is the verdict. One that does not
//! is only a suspicion (on weak geometry the cost rises faster than its
//! quadratic model and σ is conservative): the calibration then asks the
//! profile ([`crate::profile`]) and [`LinearityCheck::with_profile`] keeps
//! *unreliable* only where the profile finds σ understated.
//!
//! An exact fit (cost at the solver's exact-fit floor) has nothing to check.

use nalgebra::{DVector, Vector6};
use psdcal_model::fit::EXACT_FIT_MEAN_SQUARE_MM2;
use psdcal_solver::normal_equations::{NormalEquations, Step};
use psdcal_solver::solver::{self, Problem};
use serde::Serialize;

use crate::data::CalibrationData;
use crate::problem::calibration_problem::FitState;
use crate::refine::linearization::AtSolution;
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::uncertainty::profile::ParameterProfile;
use crate::CalibError;
use psdcal_solver::solver::RobustLoss;

/// Largest accepted `|ρ − 1|` (module documentation): beyond it the
/// profile is asked. From the coverage experiment (EXPERIMENTS.md,
/// "Uncertainty that holds"): the wide scenarios stay below (median 0.001,
/// p90 0.03) and lens 2 at 0.05 mm, whose σ covers, reaches 0.25–0.43;
/// lens 1 at 0.05 mm (median 8) and weak-geometry 40 dB fits (up to 260)
/// go beyond.
pub const LINEARITY_TOLERANCE: f64 = 0.5;

/// The cost rise at `θ̂ ± 3σ_k` over its quadratic prediction.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterLinearity {
    /// The freed parameter.
    pub name: String,
    /// `ρ` at `θ̂ − 3σ_k`.
    pub minus: f64,
    /// `ρ` at `θ̂ + 3σ_k`.
    pub plus: f64,
}

impl ParameterLinearity {
    /// `max |ρ − 1|` of the two sides (infinite when a side cannot be evaluated).
    pub fn departure(&self) -> f64 {
        let d = (self.minus - 1.0).abs().max((self.plus - 1.0).abs());
        if d.is_nan() {
            f64::INFINITY
        } else {
            d
        }
    }
}

/// Whether the reported covariance can be trusted as a 3σ statement.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "verdict")]
pub enum UncertaintyVerdict {
    /// The cost is quadratic to within [`LINEARITY_TOLERANCE`] at ±3σ of
    /// every freed parameter (or the fit is exact).
    Reliable,
    /// It is not; `reason` names the parameters (the diagnostics'
    /// `uncertainty_unreliable`).
    Unreliable {
        /// One sentence for the user.
        reason: String,
    },
}

impl UncertaintyVerdict {
    /// `true` for [`UncertaintyVerdict::Reliable`].
    pub fn is_reliable(&self) -> bool {
        matches!(self, Self::Reliable)
    }
}

/// The check of a fit's linear covariance (module documentation).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinearityCheck {
    /// Per freed parameter, in covariance order (empty for an exact fit).
    pub parameters: Vec<ParameterLinearity>,
    /// The profile at ±3σ ([`crate::profile`]), when the walk found the
    /// cost not quadratic and the profile was asked (empty otherwise).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub profile: Vec<ParameterProfile>,
    /// The verdict.
    pub verdict: UncertaintyVerdict,
}

impl LinearityCheck {
    /// The verdict once the profile (`profile`, of the same fit) has been
    /// asked: a walk that found the cost quadratic stands; otherwise σ is
    /// unreliable only where the profile says it understates the
    /// uncertainty (`ParameterProfile::understated`), or for a parameter
    /// the walk flagged and the profile could not hold (a gain).
    pub fn with_profile(mut self, profile: Vec<ParameterProfile>) -> Self {
        if self.verdict.is_reliable() {
            return self;
        }
        let unprofiled = self.parameters.iter().filter(|p| {
            p.departure() > LINEARITY_TOLERANCE && profile.iter().all(|q| q.name != p.name)
        });
        let mut bad: Vec<String> = profile
            .iter()
            .filter(|p| p.understated())
            .map(|p| format!("{} ({:.2}, {:.2})", p.name, p.minus, p.plus))
            .collect();
        bad.extend(unprofiled.map(|p| format!("{} (not profiled)", p.name)));
        self.verdict = if bad.is_empty() {
            UncertaintyVerdict::Reliable
        } else {
            UncertaintyVerdict::Unreliable {
                reason: format!(
                    "the cost is not quadratic within ±3σ and its profile rises less than a quarter \
                     of the quadratic rise (or falls) at ±3σ of {}: the likelihood's interval is more \
                     than twice the reported σ, which may not cover the truth; add images or lower \
                     the noise, or use --uncertainty bootstrap:N",
                    bad.join(", ")
                ),
            }
        };
        self.profile = profile;
        self
    }
}

/// Checks the quadratic model of the cost at `refined` (module documentation).
pub fn check_linearity(
    data: &CalibrationData,
    refined: &Refined,
    options: &RefineOptions,
) -> Result<LinearityCheck, CalibError> {
    let at = AtSolution::new(data, refined, options)?;
    check_linearity_at(&at, data, options)
}

/// [`check_linearity`] from the fit already linearised at its solution.
pub(crate) fn check_linearity_at(
    at: &AtSolution<'_>,
    data: &CalibrationData,
    options: &RefineOptions,
) -> Result<LinearityCheck, CalibError> {
    let fit = FitAtSolution {
        problem: &at.problem,
        state: &at.state,
        ne: &at.ne,
        names: &options.free_names(),
        // A prior's residuals count as observations (augmented regression).
        observations: 2 * data.point_count() + at.problem.prior().map_or(0, |p| p.len()),
        robust: options.robust,
    };
    check_quadratic(&fit, None)
}

/// Any fit of model parameters and one pose per image linearised at its
/// solution: what the check walks on.
pub struct FitAtSolution<'f, P> {
    /// The fit's problem (its cost is the one checked).
    pub problem: &'f P,
    /// The solution.
    pub state: &'f FitState,
    /// The undamped normal equations at the solution.
    pub ne: &'f NormalEquations,
    /// The freed parameters' names, in the problem's column order.
    pub names: &'f [String],
    /// Residual coordinates (`2 ·` points).
    pub observations: usize,
    /// The fit's robust loss.
    pub robust: Option<RobustLoss>,
}

/// The check (module documentation) of any fit at its solution.
/// `reported`: each freed parameter's reported σ when it is not the
/// linear `σ_lin` (a covariance with more than the measurement noise, such
/// as the survey's): the walk then goes to `±3σ_k` along the same
/// direction, where the quadratic model predicts the rise
/// `9 σ_k² / S⁻¹_kk`, and `ρ` is the actual rise over that.
pub fn check_quadratic<P>(
    fit: &FitAtSolution<'_, P>,
    reported: Option<&[f64]>,
) -> Result<LinearityCheck, CalibError>
where
    P: Problem<State = FitState, Error = CalibError>,
{
    let (problem, state, ne, names) = (fit.problem, fit.state, fit.ne, fit.names);
    let base = solver::cost(problem, state, fit.robust)?;
    let observations = fit.observations;
    let unknowns = names.len() + 6 * state.poses.len();
    // An exact fit (the solver's own criterion, per point of two
    // coordinates): nothing to check.
    let exact = EXACT_FIT_MEAN_SQUARE_MM2 * observations as f64 / 2.0;
    if observations <= unknowns || base <= exact {
        return Ok(LinearityCheck {
            parameters: Vec::new(),
            profile: Vec::new(),
            verdict: UncertaintyVerdict::Reliable,
        });
    }
    let s2 = base / (observations - unknowns) as f64;
    let (s_inv, _) = ne.inverse_blocks().ok_or_else(|| CalibError::Degenerate {
        reason: "the information matrix is singular".into(),
    })?;
    let v_inv: Vec<_> =
        ne.v.iter()
            .map(|v| v.cholesky().map(|c| c.inverse()))
            .collect::<Option<_>>()
            .ok_or_else(|| CalibError::Degenerate {
                reason: "a pose is not determined by its image's points".into(),
            })?;
    let mut parameters = Vec::with_capacity(names.len());
    for (k, name) in names.iter().enumerate() {
        let column: DVector<f64> = s_inv.column(k).into_owned();
        let sigma = match reported {
            Some(sd) => sd.get(k).copied().unwrap_or(f64::NAN),
            None => (s2 * s_inv[(k, k)]).sqrt(),
        };
        let scale = 3.0 * sigma / s_inv[(k, k)];
        // dᵀ S d with d = scale · S⁻¹ e_k (9 s² for σ_lin).
        let predicted = scale * scale * s_inv[(k, k)];
        let rho = |sign: f64| -> f64 {
            let da = &column * (sign * scale);
            let db: Vec<Vector6<f64>> =
                ne.w.iter()
                    .zip(&v_inv)
                    .map(|(w, vi)| {
                        let wt = w.transpose() * &da;
                        -vi * Vector6::from_iterator(wt.iter().copied())
                    })
                    .collect();
            let step = Step { da, db };
            problem
                .apply_step(state, &step)
                .and_then(|moved| solver::cost(problem, &moved, fit.robust).ok())
                .map_or(f64::NAN, |c| (c - base) / predicted)
        };
        parameters.push(ParameterLinearity {
            name: name.clone(),
            minus: rho(-1.0),
            plus: rho(1.0),
        });
    }
    let bad: Vec<String> = parameters
        .iter()
        .filter(|p| p.departure() > LINEARITY_TOLERANCE)
        .map(|p| format!("{} ({:.2}, {:.2})", p.name, p.minus, p.plus))
        .collect();
    let verdict = if bad.is_empty() {
        UncertaintyVerdict::Reliable
    } else {
        UncertaintyVerdict::Unreliable {
            reason: format!(
                "the cost is not quadratic within ±3σ of {} (rise over its quadratic prediction: {}); \
                 the reported σ may not cover the truth: add images or lower the noise, or use \
                 --uncertainty bootstrap:N",
                if bad.len() == 1 { "one parameter" } else { "several parameters" },
                bad.join(", ")
            ),
        }
    };
    Ok(LinearityCheck {
        parameters,
        profile: Vec::new(),
        verdict,
    })
}
