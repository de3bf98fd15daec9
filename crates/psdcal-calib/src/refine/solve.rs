//! One Levenberg–Marquardt refinement from a start, with its noise
//! reweighting passes (the conventions are documented on [`crate::refine`]):
//! [`refine`], the start model it completes, and the cost of a solution.

use psdcal_model::stages::Gains;
use psdcal_model::{CostKind, Model, Pose};
use psdcal_solver::solver::{self, SolverOptions};

use crate::data::CalibrationData;
use crate::problem::calibration_problem::{CalibrationProblem, FitState};
use crate::problem::weighting::PointWeights;
use crate::refine::options::RefineOptions;
use crate::refine::refined::{Linearization, Refined};
use crate::CalibError;

fn validate(data: &CalibrationData, poses: &[Pose]) -> Result<(), CalibError> {
    if poses.len() != data.images.len() {
        return Err(CalibError::Numerical {
            stage: "refinement",
            reason: format!("{} poses for {} images", poses.len(), data.images.len()),
        });
    }
    data.check()
}

/// The model a refinement starts from: `start`, with a gains stage (unit
/// gains) added when the options free the gains and it has none.
pub fn start_model(data: &CalibrationData, start: Model, options: &RefineOptions) -> Model {
    if options.fit_gains && start.gains_stage().is_none() {
        start.with_stages_and_gains(Some(Gains::new(data.geometry)))
    } else {
        start
    }
}

/// The solver options of a refinement.
fn solver_options(data: &CalibrationData, options: &RefineOptions) -> SolverOptions {
    let points = data.point_count() as f64;
    SolverOptions {
        max_iterations: options.max_iterations,
        cost_tolerance: options.cost_tolerance,
        step_tolerance: options.step_tolerance,
        initial_lambda: options.initial_lambda,
        exact_cost: psdcal_model::fit::EXACT_FIT_MEAN_SQUARE_MM2 * points,
        step_floor: 1e-26 * points,
        robust: options.robust,
    }
}

/// Most reweighting passes of a noise-weighted template-plane refinement.
const MAX_REWEIGHTINGS: usize = 5;
/// The weights have settled when recomputing them changes the weighted cost
/// by less than this fraction.
const REWEIGHT_TOLERANCE: f64 = 1e-6;

/// Refines the freed parameters of `start` and every pose.
///
/// With `options.fit_gains`, a model without a gains stage gets one (unit
/// gains). With a noise model other than uniform, the points are whitened
/// ([`crate::weighting`]) with weights computed at the start; when the
/// weights depend on the parameters (template-plane cost, or fitted gains)
/// they are recomputed at the solution and the refinement repeated until
/// the weighted cost changes by less than 1e-6 of itself (at most five
/// passes). Iterations add up over the passes.
pub fn refine(
    data: &CalibrationData,
    start: impl Into<Model>,
    poses: &[Pose],
    options: &RefineOptions,
) -> Result<Refined, CalibError> {
    validate(data, poses)?;
    let model = start_model(data, start.into(), options);
    model.validate()?;
    let free = options.free_names();
    let weights_at =
        |s: &FitState| PointWeights::compute(data, options.noise, options.cost, &s.model, &s.poses);
    let mut state = FitState {
        model,
        poses: poses.to_vec(),
    };
    let mut weights = weights_at(&state)?;
    let settings = solver_options(data, options);
    let problem =
        CalibrationProblem::new(data, options.cost, &state.model, &free, weights.as_ref())?
            .with_prior(&state.model, options.prior.as_ref())?;
    let mut solution = solver::solve(&problem, state, &settings)?;
    let parameter_dependent = options.cost == CostKind::Template || options.fit_gains;
    if weights.is_some() && parameter_dependent {
        for _ in 1..MAX_REWEIGHTINGS {
            if !solution.report.termination.converged() {
                break;
            }
            let next = weights_at(&solution.state)?;
            let reweighted = {
                let p = CalibrationProblem::new(
                    data,
                    options.cost,
                    &solution.state.model,
                    &[],
                    next.as_ref(),
                )?
                .with_prior(&solution.state.model, options.prior.as_ref())?;
                solver::cost(&p, &solution.state, options.robust)?
            };
            weights = next;
            if (reweighted - solution.cost).abs() <= REWEIGHT_TOLERANCE * solution.cost {
                solution.cost = reweighted;
                // Linearised with the weights before these.
                solution.normal_equations = None;
                break;
            }
            let p = CalibrationProblem::new(
                data,
                options.cost,
                &solution.state.model,
                &free,
                weights.as_ref(),
            )?
            .with_prior(&solution.state.model, options.prior.as_ref())?;
            let mut pass = solver::solve(&p, solution.state.clone(), &settings)?;
            pass.report.iterations += solution.report.iterations;
            pass.report.accepted += solution.report.accepted;
            let mut history = std::mem::take(&mut solution.report.cost_history);
            history.extend(pass.report.cost_history);
            pass.report.cost_history = history;
            solution = pass;
        }
    }
    state = solution.state;
    let linearization = solution
        .normal_equations
        .map(|ne| Linearization::new(ne, options, data, &state, weights.as_ref()));
    Ok(Refined {
        model: state.model,
        poses: state.poses,
        cost: solution.cost,
        weights,
        report: solution.report,
        linearization,
    })
}
