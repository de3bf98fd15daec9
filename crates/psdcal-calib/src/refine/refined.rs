//! What a refinement returns ([`Refined`]: the model, one pose per image,
//! the cost, the point weights and the solver's report) and the linearisation
//! it keeps with it ([`Linearization`]): the solver's last undamped normal
//! equations when they are at its solution, with everything they depend on.
//! The covariance and the linearity check take these instead of linearising
//! again (one evaluation of every point) when asked for the same fit: the
//! same options, data size, model, poses and weights. Anything else, or a
//! refinement whose fields were changed since, is linearised afresh.

use psdcal_model::{Model, Pose, SensorModel};
use psdcal_solver::normal_equations::NormalEquations;
use psdcal_solver::solver::SolverReport as RefineReport;

use crate::data::CalibrationData;
use crate::problem::calibration_problem::FitState;
use crate::problem::weighting::PointWeights;
use crate::refine::options::RefineOptions;

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

/// The undamped normal equations of a refinement at its solution, with
/// everything they depend on: [`AtSolution::new`](crate::refine::linearization::AtSolution::new) takes them instead of
/// linearising again when asked for the same fit (same options, data size,
/// model, poses and weights). A cache: it takes no part in comparisons.
#[derive(Debug, Clone)]
pub(crate) struct Linearization {
    options: RefineOptions,
    images: usize,
    points: usize,
    model: Model,
    poses: Vec<Pose>,
    weights: Option<PointWeights>,
    ne: NormalEquations,
}

impl PartialEq for Linearization {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl Linearization {
    /// The normal equations `ne` of the fit of `data` with `options` at
    /// `state`, weighted by `weights`.
    pub(crate) fn new(
        ne: NormalEquations,
        options: &RefineOptions,
        data: &CalibrationData,
        state: &FitState,
        weights: Option<&PointWeights>,
    ) -> Self {
        Self {
            options: options.clone(),
            images: data.images.len(),
            points: data.point_count(),
            model: state.model.clone(),
            poses: state.poses.clone(),
            weights: weights.cloned(),
            ne,
        }
    }

    /// The normal equations when they are those of `refined` for `options`
    /// on `data`.
    pub(crate) fn of(
        refined: &Refined,
        data: &CalibrationData,
        options: &RefineOptions,
    ) -> Option<NormalEquations> {
        let l = refined.linearization.as_ref()?;
        (l.options == *options
            && l.images == data.images.len()
            && l.points == data.point_count()
            && l.model == refined.model
            && l.poses == refined.poses
            && l.weights == refined.weights)
            .then(|| l.ne.clone())
    }
}
