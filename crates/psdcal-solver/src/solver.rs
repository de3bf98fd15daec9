//! The one solver of psdcal: Levenberg–Marquardt over a global parameter
//! block plus independent six-parameter blocks (the poses), eliminated by the
//! Schur complement ([`crate::normal_equations`]). The refinement (P29), the
//! start's profile and the preliminary correction are all problems for it.
//!
//! A [`Problem`] visits its residuals at a state ([`Problem::evaluate`]),
//! each a [`ResidualTerm`] of one or two rows with its Jacobians, and moves
//! the state by a step ([`Problem::apply_step`]). The solver owns what is
//! common:
//!
//! - the cost `Σ ρ(‖r‖²)` with an optional robust loss `ρ`
//!   ([`RobustLoss`]; Huber `ρ = s` for `s ≤ c²`, else `2c√s − c²`; Cauchy
//!   `ρ = c² ln(1 + s/c²)`), each residual's normal equations reweighted by
//!   `ρ'(s)` (iteratively reweighted least squares); per-residual weights
//!   (whitening) are the problem's, applied to `r` and its Jacobians;
//! - Marquardt's diagonal damping `(1 + λ)`, solved after Jacobi scaling,
//!   with Nielsen's update: after a step that lowers the cost `λ` falls ×1/3
//!   and `ν = 2`; after one that does not, `λ ← λν`, `ν ← 2ν`;
//! - stopping: an *exact fit* when the cost is below
//!   [`SolverOptions::exact_cost`], a negligible accepted step (the residual change
//!   `‖J δ‖ ≈ √(Σ δ_k² (JᵀJ)_kk)` below `step_tolerance · √cost`, with a
//!   rounding floor), a cost change below `cost_tolerance · cost` (accepted,
//!   or predicted by the linear model `−2gᵀδ − δᵀJᵀJδ` for a step proposed
//!   with small damping at the start or right after an accepted step that
//!   changed the cost by less than 1e-6 of itself), saturated
//!   damping (`λ > 1e16`), or the iteration budget;
//! - a [`SolverReport`] (termination, iterations, accepted steps, cost
//!   history); the last state is returned whatever the termination.

use serde::Serialize;

use crate::normal_equations::{NormalEquations, ResidualTerm, Step};

/// A robust loss on the squared norm of a residual.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum RobustLoss {
    /// Quadratic up to `scale`, linear beyond.
    Huber {
        /// Residual norm at which the loss turns linear (cost units: mm).
        scale: f64,
    },
    /// Logarithmic: outliers far beyond `scale` barely count.
    Cauchy {
        /// Residual norm scale (mm).
        scale: f64,
    },
}

impl RobustLoss {
    /// The loss's scale.
    pub fn scale(&self) -> f64 {
        match *self {
            RobustLoss::Huber { scale } | RobustLoss::Cauchy { scale } => scale,
        }
    }

    /// The same loss with its scale multiplied by `factor` (a scale given in
    /// units of the residuals' noise made absolute).
    pub fn scaled(self, factor: f64) -> Self {
        match self {
            RobustLoss::Huber { scale } => RobustLoss::Huber {
                scale: scale * factor,
            },
            RobustLoss::Cauchy { scale } => RobustLoss::Cauchy {
                scale: scale * factor,
            },
        }
    }

    /// `ρ(s)` for a squared residual norm `s`.
    pub fn rho(&self, s: f64) -> f64 {
        match *self {
            RobustLoss::Huber { scale } => {
                if s <= scale * scale {
                    s
                } else {
                    2.0 * scale * s.sqrt() - scale * scale
                }
            }
            RobustLoss::Cauchy { scale } => scale * scale * (s / (scale * scale)).ln_1p(),
        }
    }

    /// `ρ'(s)`: the weight of the residual in the reweighted normal equations.
    pub fn weight(&self, s: f64) -> f64 {
        match *self {
            RobustLoss::Huber { scale } => {
                if s <= scale * scale {
                    1.0
                } else {
                    scale / s.sqrt()
                }
            }
            RobustLoss::Cauchy { scale } => 1.0 / (1.0 + s / (scale * scale)),
        }
    }
}

/// Why the solver stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The cost is zero to rounding (noise-free data).
    ExactFit,
    /// An accepted step changed the cost by less than the tolerance.
    CostConverged,
    /// The step became negligible.
    StepConverged,
    /// The damping grew without finding a lower cost: a minimum to the
    /// precision of the arithmetic.
    DampingSaturated,
    /// The iteration budget ran out.
    MaxIterations,
}

impl Termination {
    /// Whether the solution is a converged minimum.
    pub fn converged(self) -> bool {
        !matches!(self, Termination::MaxIterations)
    }

    /// Plain-language description, for reports.
    pub fn describe(self) -> &'static str {
        match self {
            Termination::ExactFit => "exact fit (noise-free data)",
            Termination::CostConverged => "converged (cost no longer decreasing)",
            Termination::StepConverged => "converged (negligible step)",
            Termination::DampingSaturated => "converged (no lower cost to machine precision)",
            Termination::MaxIterations => "iteration budget exhausted",
        }
    }
}

/// What the solver did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolverReport {
    /// Why it stopped.
    pub termination: Termination,
    /// Iterations (solved steps, accepted or not).
    pub iterations: usize,
    /// Accepted steps.
    pub accepted: usize,
    /// Cost after each accepted step, starting with the initial cost.
    pub cost_history: Vec<f64>,
    /// Final damping.
    pub final_lambda: f64,
}

/// Options of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverOptions {
    /// Iteration budget (accepted and rejected steps both count).
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction.
    pub cost_tolerance: f64,
    /// Stop when the step changes the residuals by less than this fraction
    /// of their norm.
    pub step_tolerance: f64,
    /// Starting damping.
    pub initial_lambda: f64,
    /// Cost at or below which the fit is exact.
    pub exact_cost: f64,
    /// Rounding floor of the residual norm², below which steps count as
    /// negligible whatever the cost.
    pub step_floor: f64,
    /// Optional robust loss.
    pub robust: Option<RobustLoss>,
}

impl Default for SolverOptions {
    fn default() -> Self {
        Self {
            max_iterations: 500,
            cost_tolerance: 1e-10,
            step_tolerance: 1e-10,
            initial_lambda: 1e-3,
            exact_cost: 0.0,
            step_floor: 0.0,
            robust: None,
        }
    }
}

/// A least-squares problem: a state, its residuals and how a step moves it.
pub trait Problem {
    /// Everything that is estimated (parameters and poses).
    type State: Clone;
    /// Why a residual could not be evaluated.
    type Error;

    /// Number of free global parameters (the columns of every `a`).
    fn global_len(&self) -> usize;

    /// Number of six-parameter blocks.
    fn block_count(&self) -> usize;

    /// Visits every residual at `state`; `a` and the block Jacobian are only
    /// read when `jacobians` is true (they may be empty otherwise).
    fn evaluate(
        &self,
        state: &Self::State,
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>),
    ) -> Result<(), Self::Error>;

    /// [`Self::evaluate`] for problems whose residuals each touch a few of
    /// many global parameters (a network's sensors): a term may come with
    /// the global columns its `a` holds (`a` is then `d × columns.len()`,
    /// column-major), `None` meaning all of them. The default visits
    /// [`Self::evaluate`]'s dense terms.
    fn evaluate_sparse(
        &self,
        state: &Self::State,
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>, Option<&[usize]>),
    ) -> Result<(), Self::Error> {
        self.evaluate(state, jacobians, &mut |term| visit(term, None))
    }

    /// The state moved by `step`, or `None` when it leaves the domain (the
    /// step is then rejected like one that raises the cost).
    fn apply_step(&self, state: &Self::State, step: &Step) -> Option<Self::State>;
}

/// The solver's answer: the last state, its cost and the report.
#[derive(Debug, Clone)]
pub struct Solution<S> {
    /// The last accepted state (the start when nothing was accepted).
    pub state: S,
    /// Its cost.
    pub cost: f64,
    /// What the solver did.
    pub report: SolverReport,
    /// The undamped normal equations at `state`, when the solver holds
    /// them: it does unless an accepted step ended the solve (the last
    /// linearisation is then of the state before it). A caller that needs
    /// them at the solution (the covariance) saves one evaluation.
    pub normal_equations: Option<NormalEquations>,
}

/// Relative cost decrease of an accepted step below which the iteration counts
/// as near a minimum (then a negligible predicted decrease stops it).
const SETTLED: f64 = 1e-6;

/// The cost `Σ ρ(‖r‖²)` of a problem at a state.
pub fn cost<P: Problem>(
    problem: &P,
    state: &P::State,
    robust: Option<RobustLoss>,
) -> Result<f64, P::Error> {
    let mut total = 0.0;
    problem.evaluate(state, false, &mut |term| {
        let s: f64 = term.r.iter().map(|r| r * r).sum();
        total += robust.map_or(s, |l| l.rho(s));
    })?;
    Ok(total)
}

/// The normal equations of a problem at a state (robustly reweighted).
pub fn normal_equations<P: Problem>(
    problem: &P,
    state: &P::State,
    robust: Option<RobustLoss>,
) -> Result<NormalEquations, P::Error> {
    normal_equations_and_cost(problem, state, robust).map(|(ne, _)| ne)
}

/// [`normal_equations`] with the cost of the same residuals (summed as
/// [`cost`] sums them), from one evaluation.
fn normal_equations_and_cost<P: Problem>(
    problem: &P,
    state: &P::State,
    robust: Option<RobustLoss>,
) -> Result<(NormalEquations, f64), P::Error> {
    let mut ne = NormalEquations::zeros(problem.global_len(), problem.block_count());
    let mut total = 0.0;
    problem.evaluate_sparse(state, true, &mut |term, columns| {
        let s: f64 = term.r.iter().map(|r| r * r).sum();
        total += robust.map_or(s, |l| l.rho(s));
        let weight = robust.map_or(1.0, |l| l.weight(s));
        match columns {
            None => ne.add(weight, term),
            Some(columns) => ne.add_columns(weight, term, columns),
        }
    })?;
    ne.finish();
    Ok((ne, total))
}

/// Minimises the problem's cost from `start` (module documentation). Fails
/// only when the start itself cannot be evaluated.
pub fn solve<P: Problem>(
    problem: &P,
    start: P::State,
    options: &SolverOptions,
) -> Result<Solution<P::State>, P::Error> {
    let robust = options.robust;
    let mut state = start;
    // The start's cost comes with its linearisation (one evaluation).
    let (mut ne, mut cost_now) = normal_equations_and_cost(problem, &state, robust)?;
    let mut history = vec![cost_now];
    let (mut lambda, mut nu) = (options.initial_lambda, 2.0);
    let (mut iterations, mut accepted) = (0, 0);
    // Whether the last accepted step changed the cost by less than SETTLED
    // of itself (the iteration is near a minimum, where the linear model's
    // prediction is to be trusted).
    let mut settled = false;
    // Whether `ne` is the linearisation at `state`.
    let mut current = true;
    let termination = loop {
        if cost_now <= options.exact_cost {
            break Termination::ExactFit;
        }
        if iterations >= options.max_iterations {
            break Termination::MaxIterations;
        }
        if lambda > 1e16 {
            break Termination::DampingSaturated;
        }
        iterations += 1;
        let Some(step) = ne.solve(lambda) else {
            lambda *= nu;
            nu *= 2.0;
            continue;
        };
        // In the Gauss–Newton regime (small damping, no rejection since the
        // last accepted step), a step whose predicted decrease of the cost is
        // below the tolerance means the minimum is reached to the precision
        // asked: stop without spending rejected trials on rounding.
        if nu == 2.0
            && lambda <= 1e-2
            && (accepted == 0 || settled)
            && ne.predicted_decrease(&step) <= options.cost_tolerance * cost_now
        {
            break Termination::CostConverged;
        }
        let trial = problem.apply_step(&state, &step);
        let trial_cost = trial
            .as_ref()
            .and_then(|t| cost(problem, t, robust).ok())
            .filter(|c| c.is_finite())
            .unwrap_or(f64::INFINITY);
        match trial {
            Some(next) if trial_cost < cost_now => {
                let small_step = step_is_negligible(&ne, &step, cost_now, options);
                let small_change = (cost_now - trial_cost) <= options.cost_tolerance * cost_now;
                settled = (cost_now - trial_cost) <= SETTLED * cost_now;
                state = next;
                cost_now = trial_cost;
                history.push(cost_now);
                accepted += 1;
                lambda = (lambda / 3.0).max(1e-15);
                nu = 2.0;
                if small_step || small_change {
                    current = false;
                    break if small_step {
                        Termination::StepConverged
                    } else {
                        Termination::CostConverged
                    };
                }
                match normal_equations(problem, &state, robust) {
                    Ok(next_ne) => ne = next_ne,
                    // The accepted state evaluates (its cost is finite), so
                    // this cannot happen; stop on the state reached.
                    Err(_) => {
                        current = false;
                        break Termination::DampingSaturated;
                    }
                }
            }
            _ => {
                lambda *= nu;
                nu *= 2.0;
            }
        }
    };
    Ok(Solution {
        state,
        cost: cost_now,
        report: SolverReport {
            termination,
            iterations,
            accepted,
            cost_history: history,
            final_lambda: lambda,
        },
        normal_equations: current.then_some(ne),
    })
}

/// Whether a step is negligible: the change it makes to the residuals,
/// `‖J δ‖ ≈ sqrt(Σ δ_k² diag(JᵀJ)_k)`, is below `step_tolerance` times the
/// residual norm `sqrt(cost)` (with the rounding floor for exact data). One
/// threshold thus serves `f` (mm) and `k3` (mm⁻⁶) alike.
fn step_is_negligible(
    ne: &NormalEquations,
    step: &Step,
    cost: f64,
    options: &SolverOptions,
) -> bool {
    let mut change2 = 0.0;
    for k in 0..step.da.len() {
        change2 += step.da[k] * step.da[k] * ne.u[(k, k)];
    }
    for (i, db) in step.db.iter().enumerate() {
        for k in 0..6 {
            change2 += db[k] * db[k] * ne.v[i][(k, k)];
        }
    }
    let tolerance = options.step_tolerance;
    change2 <= tolerance * tolerance * cost.max(options.step_floor)
}
