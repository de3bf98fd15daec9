//! Levenberg–Marquardt refinement of the sensor parameters and every pose
//! (MODEL.md §4.6, the paper's (P29)).
//!
//! Cost (template plane, the default): for every observed point `m_ij` of LED
//! `j` in image `i`,
//!
//! ```text
//! r_ij = back_project(θ, pose_i, m_ij) − (X_j, Y_j),   cost = Σ ‖r_ij‖²   (mm²)
//! ```
//!
//! i.e. the measured point is corrected for distortion, its ray is cut with
//! the template plane of its pose and compared with the LED. `cost` is the
//! paper's *residual*. The image-plane alternative is
//! `r_ij = project(θ, pose_i, X_j, Y_j) − m_ij` (mm on the sensor).
//!
//! With a robust loss `ρ` of scale `c` on `s = ‖r‖²` (Huber:
//! `ρ = s` for `s ≤ c²`, else `2c√s − c²`; Cauchy: `ρ = c² ln(1 + s/c²)`), the
//! cost is `Σ ρ(s_ij)` and each step reweights the normal equations with
//! `ρ'(s_ij)` (iteratively reweighted least squares).
//!
//! Each iteration solves the damped normal equations through the Schur
//! complement on the pose blocks ([`crate::normal_equations`]) with
//! Marquardt's diagonal damping `(1 + λ)`, updated as Nielsen proposes: after
//! a step that lowers the cost `λ` falls ×1/3 and `ν = 2`; after one that does
//! not, `λ ← λν`, `ν ← 2ν` (so a run of rejections ends within about ten
//! steps). Poses are updated additively in `(rvec, t)`.
//!
//! Stopping: an *exact fit* when the RMS residual is below 1e-10 (mm on the
//! template plane; a few hundred times the rounding floor of the
//! back-projection), a negligible step or cost change, saturated damping, or
//! the iteration budget.

use nalgebra::Matrix2x3;
use nalgebra::{SMatrix, Vector2};
use psdcal_model::sensor::impact_point_gain_jacobian;
use psdcal_model::{ChannelGains, Param, Pose, RotationJacobian, SensorModel, N_PARAMS};
use serde::Serialize;

use crate::data::CalibrationData;
use crate::normal_equations::{FullNormalEquations, NormalEquations, N_GLOBAL};
use crate::weighting::{NoiseModel, PointWeights};
use crate::CalibError;

/// Mean squared residual per point below which the fit is exact (RMS 1e-10).
const EXACT_FIT_MS: f64 = 1e-20;

/// Which error the refinement minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CostKind {
    /// Template-plane error (P29), mm on the template: the paper's choice.
    Template,
    /// Image-plane reprojection error, mm on the sensor.
    Image,
}

/// A robust loss on the squared norm of a point's residual.
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

/// Options of [`refine`].
#[derive(Debug, Clone, PartialEq)]
pub struct RefineOptions {
    /// The cost minimised.
    pub cost: CostKind,
    /// The freed sensor parameters (the others stay at their start values).
    pub free: Vec<Param>,
    /// Also estimate the relative channel gains `g_x2, g_y1, g_y2` (issue 7):
    /// needs the data's amplitudes; every impact point is then recomputed
    /// from its amplitudes divided by the current gains (MODEL.md §1).
    pub fit_gains: bool,
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
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            cost: CostKind::Template,
            free: vec![Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2],
            noise: NoiseModel::Uniform,
            robust: None,
            fit_gains: false,
            max_iterations: 500,
            cost_tolerance: 1e-10,
            step_tolerance: 1e-10,
            initial_lambda: 1e-3,
        }
    }
}

/// Why the refinement stopped.
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
}

/// What the refinement did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RefineReport {
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

/// The refined parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// Sensor parameters.
    pub model: SensorModel,
    /// Relative channel gains (the start's when not fitted).
    pub gains: ChannelGains,
    /// One `sensor_from_template` pose per image.
    pub poses: Vec<Pose>,
    /// Final cost (robust cost when a loss is set; weighted by `weights`
    /// under a noise model).
    pub cost: f64,
    /// The point weights of the final cost (`None`: unweighted).
    pub weights: Option<PointWeights>,
    /// The solver's report.
    pub report: RefineReport,
}

/// Residual of one observation (no Jacobians).
pub fn residual(
    data: &CalibrationData,
    cost: CostKind,
    model: &SensorModel,
    pose: &Pose,
    led: usize,
    measured: &Vector2<f64>,
) -> Result<Vector2<f64>, psdcal_model::ModelError> {
    let xy = data.template[led];
    Ok(match cost {
        CostKind::Template => model.back_project(pose, measured)? - xy,
        CostKind::Image => model.project(pose, &xy)? - measured,
    })
}

/// A residual with its Jacobians with respect to the global parameters
/// (2×14: model, then gains) and the pose (2×6).
type ResidualWithJacobians = (Vector2<f64>, SMatrix<f64, 2, N_GLOBAL>, SMatrix<f64, 2, 6>);

/// The measured point of observation `k` of image `i`: the stored point, or,
/// with `gains`, the point recomputed from its amplitudes divided by them,
/// with its Jacobian with respect to `(g_x2, g_y1, g_y2)`.
pub fn measured_point(
    data: &CalibrationData,
    i: usize,
    k: usize,
    gains: Option<&ChannelGains>,
) -> Result<(Vector2<f64>, Option<Matrix2x3<f64>>), psdcal_model::ModelError> {
    match (gains, data.amplitudes.as_ref()) {
        (Some(g), Some(amps)) => {
            let (m, j) = impact_point_gain_jacobian(&data.geometry, &amps[i][k], g)?;
            Ok((m, Some(j)))
        }
        _ => Ok((data.images[i].points[k].measured, None)),
    }
}

/// Residual of one observation with its Jacobians with respect to every
/// global parameter and to the pose. `dm_dg` is the measured point's
/// Jacobian with respect to the gains, when they are estimated.
// The arguments are the point's whole context on the solver's hot path;
// bundling them would only add a struct built per point.
#[allow(clippy::too_many_arguments)]
fn residual_with_jacobians(
    data: &CalibrationData,
    cost: CostKind,
    model: &SensorModel,
    pose: &Pose,
    rotation: &RotationJacobian,
    led: usize,
    measured: &Vector2<f64>,
    dm_dg: Option<&Matrix2x3<f64>>,
) -> Result<ResidualWithJacobians, psdcal_model::ModelError> {
    let xy = data.template[led];
    let mut a = SMatrix::<f64, 2, N_GLOBAL>::zeros();
    let (r, b) = match cost {
        CostKind::Template => {
            let (p, j) = model.back_project_with_jacobians_using(pose, rotation, measured)?;
            a.fixed_view_mut::<2, N_PARAMS>(0, 0)
                .copy_from(&j.wrt_model);
            if let Some(g) = dm_dg {
                a.fixed_view_mut::<2, 3>(0, N_PARAMS)
                    .copy_from(&(j.wrt_measured * g));
            }
            (p - xy, j.wrt_pose)
        }
        CostKind::Image => {
            let (p, j) = model.project_with_jacobians_using(pose, rotation, &xy)?;
            a.fixed_view_mut::<2, N_PARAMS>(0, 0)
                .copy_from(&j.wrt_model);
            if let Some(g) = dm_dg {
                a.fixed_view_mut::<2, 3>(0, N_PARAMS).copy_from(&(-g));
            }
            (p - measured, j.wrt_pose)
        }
    };
    Ok((r, a, b))
}

/// The global columns of the freed parameters (and of the gains).
pub(crate) fn free_columns(free: &[Param], fit_gains: bool) -> Vec<usize> {
    let mut cols: Vec<usize> = free.iter().map(|p| p.index()).collect();
    if fit_gains {
        cols.extend(N_PARAMS..N_GLOBAL);
    }
    cols
}

/// Total cost, or the first observation that cannot be evaluated.
pub fn total_cost(
    data: &CalibrationData,
    cost: CostKind,
    robust: Option<RobustLoss>,
    model: &SensorModel,
    poses: &[Pose],
) -> Result<f64, (usize, usize, psdcal_model::ModelError)> {
    total_cost_with_gains(data, cost, robust, model, None, poses)
}

/// [`total_cost`] with the measured points recomputed from the amplitudes
/// with `gains` (when given).
pub fn total_cost_with_gains(
    data: &CalibrationData,
    cost: CostKind,
    robust: Option<RobustLoss>,
    model: &SensorModel,
    gains: Option<&ChannelGains>,
    poses: &[Pose],
) -> Result<f64, (usize, usize, psdcal_model::ModelError)> {
    weighted_cost(data, cost, robust, model, gains, poses, None)
}

/// [`total_cost_with_gains`] with every residual whitened by `weights`.
pub(crate) fn weighted_cost(
    data: &CalibrationData,
    cost: CostKind,
    robust: Option<RobustLoss>,
    model: &SensorModel,
    gains: Option<&ChannelGains>,
    poses: &[Pose],
    weights: Option<&PointWeights>,
) -> Result<f64, (usize, usize, psdcal_model::ModelError)> {
    let mut total = 0.0;
    for (i, image) in data.images.iter().enumerate() {
        for (k, obs) in image.points.iter().enumerate() {
            let (m, _) = measured_point(data, i, k, gains).map_err(|e| (i, k, e))?;
            let mut r =
                residual(data, cost, model, &poses[i], obs.led, &m).map_err(|e| (i, k, e))?;
            if let Some(w) = weights {
                r = w.get(i, k) * r;
            }
            let s = r.norm_squared();
            total += robust.map_or(s, |l| l.rho(s));
        }
    }
    Ok(total)
}

/// Accumulates the normal equations at the current parameters.
// The cost's definition (kind, loss, weights) and the evaluation point
// (model, gains, poses), as in `weighted_cost`, plus the freed columns.
#[allow(clippy::too_many_arguments)]
pub(crate) fn normal_equations(
    data: &CalibrationData,
    cost: CostKind,
    free: &[usize],
    robust: Option<RobustLoss>,
    model: &SensorModel,
    gains: Option<&ChannelGains>,
    poses: &[Pose],
    weights: Option<&PointWeights>,
) -> Result<NormalEquations, CalibError> {
    let mut ne = FullNormalEquations::zeros(data.images.len());
    for (i, image) in data.images.iter().enumerate() {
        let rotation = poses[i].rotation_jacobian();
        for (k, obs) in image.points.iter().enumerate() {
            let (m, dm_dg) =
                measured_point(data, i, k, gains).map_err(|e| point_error(data, i, obs.led, e))?;
            let (mut r, mut a, mut b) = residual_with_jacobians(
                data,
                cost,
                model,
                &poses[i],
                &rotation,
                obs.led,
                &m,
                dm_dg.as_ref(),
            )
            .map_err(|e| point_error(data, i, obs.led, e))?;
            if let Some(w) = weights {
                let w = w.get(i, k);
                r = w * r;
                a = w * a;
                b = w * b;
            }
            let weight = robust.map_or(1.0, |l| l.weight(r.norm_squared()));
            ne.add(i, weight, &r, &a, &b);
        }
    }
    Ok(ne.select(free))
}

fn point_error(
    data: &CalibrationData,
    image: usize,
    led: usize,
    e: psdcal_model::ModelError,
) -> CalibError {
    CalibError::Numerical {
        stage: "refinement",
        reason: format!("image '{}', LED #{}: {e}", data.images[image].id, led + 1),
    }
}

fn validate(data: &CalibrationData, poses: &[Pose], free: &[Param]) -> Result<(), CalibError> {
    if poses.len() != data.images.len() {
        return Err(CalibError::Numerical {
            stage: "refinement",
            reason: format!("{} poses for {} images", poses.len(), data.images.len()),
        });
    }
    for image in &data.images {
        for obs in &image.points {
            if obs.led >= data.template.len() {
                return Err(CalibError::UnknownLed {
                    led: obs.led,
                    template_len: data.template.len(),
                });
            }
        }
    }
    let mut seen = [false; N_PARAMS];
    for p in free {
        if std::mem::replace(&mut seen[p.index()], true) {
            return Err(CalibError::Numerical {
                stage: "refinement",
                reason: format!("parameter {p} freed twice"),
            });
        }
    }
    Ok(())
}

/// Refines `model` (its `free` parameters) and every pose from `start`.
pub fn refine(
    data: &CalibrationData,
    model: &SensorModel,
    poses: &[Pose],
    options: &RefineOptions,
) -> Result<Refined, CalibError> {
    refine_with_gains(data, model, &ChannelGains::UNIT, poses, options)
}

/// Most reweighting passes of a noise-weighted template-plane refinement.
const MAX_REWEIGHTINGS: usize = 5;
/// The weights have settled when recomputing them changes the weighted cost
/// by less than this fraction.
const REWEIGHT_TOLERANCE: f64 = 1e-6;

/// [`refine`] from given channel gains; with `options.fit_gains` they are
/// estimated too (the data must carry amplitudes).
///
/// With a noise model other than uniform, the points are whitened
/// ([`crate::weighting`]) with weights computed at the start; when the
/// weights depend on the parameters (template-plane cost, or fitted gains)
/// they are recomputed at the solution and the refinement repeated until
/// the weighted cost changes by less than 1e-6 of itself (at most five
/// passes). Iterations add up over the passes; the cost history restarts
/// its descent at each pass.
pub fn refine_with_gains(
    data: &CalibrationData,
    model: &SensorModel,
    gains: &ChannelGains,
    poses: &[Pose],
    options: &RefineOptions,
) -> Result<Refined, CalibError> {
    validate(data, poses, &options.free)?;
    if options.fit_gains && !data.has_amplitudes() {
        return Err(CalibError::InvalidInput {
            reason: "estimating the channel gains needs the electrode amplitudes of every point (signals.csv)".into(),
        });
    }
    gains.validate()?;
    let weights_at = |m: &SensorModel, g: &ChannelGains, p: &[Pose]| {
        PointWeights::compute(
            data,
            options.noise,
            options.cost,
            m,
            gains_in_cost(options, g).as_ref(),
            p,
        )
    };
    let mut weights = weights_at(model, gains, poses)?;
    let mut result = levenberg_marquardt(data, model, gains, poses, options, weights.as_ref())?;
    let parameter_dependent = options.cost == CostKind::Template || options.fit_gains;
    if weights.is_some() && parameter_dependent {
        for _ in 1..MAX_REWEIGHTINGS {
            if !result.report.termination.converged() {
                break;
            }
            let next = weights_at(&result.model, &result.gains, &result.poses)?;
            let reweighted = weighted_cost(
                data,
                options.cost,
                options.robust,
                &result.model,
                gains_in_cost(options, &result.gains).as_ref(),
                &result.poses,
                next.as_ref(),
            )
            .map_err(|(i, k, e)| point_error(data, i, data.images[i].points[k].led, e))?;
            weights = next;
            let settled = (reweighted - result.cost).abs() <= REWEIGHT_TOLERANCE * result.cost;
            if settled {
                result.cost = reweighted;
                break;
            }
            let pass = levenberg_marquardt(
                data,
                &result.model,
                &result.gains,
                &result.poses,
                options,
                weights.as_ref(),
            )?;
            let mut report = pass.report.clone();
            report.iterations += result.report.iterations;
            report.accepted += result.report.accepted;
            let mut history = std::mem::take(&mut result.report.cost_history);
            history.extend(report.cost_history);
            report.cost_history = history;
            result = Refined { report, ..pass };
        }
    }
    result.weights = weights;
    Ok(result)
}

/// The gains the cost recomputes the points with: the current ones when they
/// are estimated, none (the stored points) otherwise.
fn gains_in_cost(options: &RefineOptions, gains: &ChannelGains) -> Option<ChannelGains> {
    options.fit_gains.then_some(*gains)
}

/// One Levenberg–Marquardt run with fixed point weights.
fn levenberg_marquardt(
    data: &CalibrationData,
    model: &SensorModel,
    gains: &ChannelGains,
    poses: &[Pose],
    options: &RefineOptions,
    weights: Option<&PointWeights>,
) -> Result<Refined, CalibError> {
    let columns = free_columns(&options.free, options.fit_gains);
    let mut model = *model;
    let mut gains = *gains;
    let mut poses = poses.to_vec();
    let mut cost = weighted_cost(
        data,
        options.cost,
        options.robust,
        &model,
        gains_in_cost(options, &gains).as_ref(),
        &poses,
        weights,
    )
    .map_err(|(i, k, e)| point_error(data, i, data.images[i].points[k].led, e))?;
    let mut history = vec![cost];
    let mut lambda = options.initial_lambda;
    let mut nu = 2.0;
    let mut iterations = 0;
    let mut accepted = 0;
    let mut ne = normal_equations(
        data,
        options.cost,
        &columns,
        options.robust,
        &model,
        gains_in_cost(options, &gains).as_ref(),
        &poses,
        weights,
    )?;
    let termination = loop {
        if cost <= EXACT_FIT_MS * data.point_count() as f64 {
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
        let mut trial_model = model;
        for (k, p) in options.free.iter().enumerate() {
            trial_model.set(*p, model.get(*p) + step.da[k]);
        }
        let mut trial_gains = gains;
        if options.fit_gains {
            let n = options.free.len();
            trial_gains.x2 += step.da[n];
            trial_gains.y1 += step.da[n + 1];
            trial_gains.y2 += step.da[n + 2];
        }
        let trial_poses: Vec<Pose> = poses
            .iter()
            .zip(&step.db)
            .map(|(pose, d)| {
                let a = pose.to_array();
                Pose::from_array(&std::array::from_fn(|k| a[k] + d[k]))
            })
            .collect();
        let trial_cost = if trial_model.validate().is_ok() && trial_gains.validate().is_ok() {
            weighted_cost(
                data,
                options.cost,
                options.robust,
                &trial_model,
                gains_in_cost(options, &trial_gains).as_ref(),
                &trial_poses,
                weights,
            )
            .unwrap_or(f64::INFINITY)
        } else {
            f64::INFINITY
        };
        if trial_cost < cost {
            let small_step =
                step_is_negligible(&ne, &step, cost, data.point_count(), options.step_tolerance);
            let small_change = (cost - trial_cost) <= options.cost_tolerance * cost;
            model = trial_model;
            gains = trial_gains;
            poses = trial_poses;
            cost = trial_cost;
            history.push(cost);
            accepted += 1;
            lambda = (lambda / 3.0).max(1e-15);
            nu = 2.0;
            if small_step {
                break Termination::StepConverged;
            }
            if small_change {
                break Termination::CostConverged;
            }
            ne = normal_equations(
                data,
                options.cost,
                &columns,
                options.robust,
                &model,
                gains_in_cost(options, &gains).as_ref(),
                &poses,
                weights,
            )?;
        } else {
            lambda *= nu;
            nu *= 2.0;
        }
    };
    Ok(Refined {
        model,
        gains,
        poses,
        cost,
        weights: None,
        report: RefineReport {
            termination,
            iterations,
            accepted,
            cost_history: history,
            final_lambda: lambda,
        },
    })
}

/// Whether a step is negligible: the change it makes to the residuals,
/// `‖J δ‖ ≈ sqrt(Σ δ_k² diag(JᵀJ)_k)` (mm), is below `tolerance` times the
/// residual norm `sqrt(cost)` (with a floor at rounding level, 1e-13 mm per
/// point, for exact data). One threshold thus serves `f` (mm) and `k3`
/// (mm⁻⁶) alike.
fn step_is_negligible(
    ne: &NormalEquations,
    step: &crate::normal_equations::Step,
    cost: f64,
    points: usize,
    tolerance: f64,
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
    let floor = 1e-26 * points as f64;
    change2 <= tolerance * tolerance * cost.max(floor)
}
