//! One Levenberg–Marquardt refinement from a start, with its noise
//! reweighting passes (the conventions are documented on [`crate::refine`]):
//! [`refine`], the start model it completes, and the cost of a solution.

use psdcal_model::stages::gains::GAIN_NAMES;
use psdcal_model::stages::Gains;
use psdcal_model::{Model, Param, Pose, SensorModel};
use psdcal_solver::solver::{self, SolverOptions};

use crate::data::CalibrationData;
pub use crate::problem::calibration_problem::{CalibrationProblem, FitState};
use crate::problem::prior::Prior;
use crate::problem::weighting::{NoiseModel, PointWeights};
use crate::refine::linearization::Linearization;
use crate::CalibError;

pub use psdcal_solver::solver::{RobustLoss, SolverReport as RefineReport, Termination};

/// Mean squared residual per point below which the fit is exact (RMS 1e-10).
const EXACT_FIT_MS: f64 = 1e-20;

/// Which error the refinement minimises (defined once, in psdcal-model: the
/// same enum is calibration.json's `fit.cost`).
pub use psdcal_model::CostKind;

/// Options of [`refine`].
#[derive(Debug, Clone, PartialEq)]
pub struct RefineOptions {
    /// The cost minimised.
    pub cost: CostKind,
    /// The freed standard parameters (the others stay at their start values).
    pub free: Vec<Param>,
    /// Also estimate the relative channel gains `g_x2, g_y1, g_y2`: needs the
    /// data's amplitudes; every impact point is then recomputed from its
    /// amplitudes divided by the current gains (docs/model.md §1).
    pub fit_gains: bool,
    /// Freed parameters of the model's other stages, by name.
    pub free_stage_parameters: Vec<String>,
    /// How the points' noise is weighted ([`crate::weighting`]; uniform,
    /// the paper's unweighted cost, by default).
    pub noise: NoiseModel,
    /// Optional robust loss (off by default).
    pub robust: Option<RobustLoss>,
    /// Iteration budget (accepted and rejected steps both count).
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction.
    pub cost_tolerance: f64,
    /// Stop when the step changes the residuals by less than this fraction
    /// of their norm.
    pub step_tolerance: f64,
    /// Starting damping.
    pub initial_lambda: f64,
    /// A Gaussian prior on some freed parameters (none by default): its
    /// residuals join the cost ([`crate::prior`]).
    pub prior: Option<Prior>,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            cost: CostKind::Template,
            free: vec![Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2],
            noise: NoiseModel::Uniform,
            robust: None,
            fit_gains: false,
            free_stage_parameters: Vec::new(),
            max_iterations: 500,
            cost_tolerance: 1e-10,
            step_tolerance: 1e-10,
            initial_lambda: 1e-3,
            prior: None,
        }
    }
}

impl RefineOptions {
    /// Names of every freed parameter, in covariance order: the standard
    /// ones as listed, the gains, then the other stages'.
    pub fn free_names(&self) -> Vec<String> {
        let mut names: Vec<String> = self.free.iter().map(|p| p.name().to_string()).collect();
        if self.fit_gains {
            names.extend(GAIN_NAMES.iter().map(|n| n.to_string()));
        }
        names.extend(self.free_stage_parameters.iter().cloned());
        names
    }
}

/// The refined parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// The model (every stage's parameters; the gains when it owns them).
    pub model: Model,
    /// One `sensor_from_template` pose per image.
    pub poses: Vec<Pose>,
    /// Final cost (robust cost when a loss is set; weighted by `weights`
    /// under a noise model).
    pub cost: f64,
    /// The point weights of the final cost (`None`: unweighted).
    pub weights: Option<PointWeights>,
    /// The solver's report.
    pub report: RefineReport,
    /// The solver's last linearisation, when it is at this solution.
    pub(crate) linearization: Option<Linearization>,
}

impl Refined {
    /// The standard parameters of the refined model.
    pub fn sensor_model(&self) -> SensorModel {
        self.model.sensor_model()
    }
}

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
        exact_cost: EXACT_FIT_MS * points,
        step_floor: 1e-26 * points,
        robust: options.robust,
    }
}

/// Total cost of `(model, poses)` (robust when a loss is given).
pub fn total_cost(
    data: &CalibrationData,
    cost: CostKind,
    robust: Option<RobustLoss>,
    model: &Model,
    poses: &[Pose],
) -> Result<f64, CalibError> {
    let problem = CalibrationProblem::new(data, cost, model, &[], None)?;
    let state = FitState {
        model: model.clone(),
        poses: poses.to_vec(),
    };
    solver::cost(&problem, &state, robust)
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
