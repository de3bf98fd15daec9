//! The calibration cost of a data set as a [`Problem`] for the one solver
//! (docs/model.md §4.6, the paper's (P29)): the model's freed parameters are
//! the global block, each image's `sensor_from_template` pose a block of six.
//!
//! Cost (template plane, the default): for every observed point `m_ij` of LED
//! `j` in image `i`,
//!
//! ```text
//! r_ij = back_project(θ, pose_i, m_ij) − (X_j, Y_j),   cost = Σ ‖r_ij‖²   (mm²)
//! ```
//!
//! i.e. the measured point is corrected through the model's chain, its ray
//! is cut with the template plane of its pose and compared with the LED.
//! `cost` is the paper's *residual*. The image-plane alternative is
//! `r_ij = project(θ, pose_i, X_j, Y_j) − m_ij` (mm on the sensor).
//!
//! The freed parameters are any of the model's, by name: the standard ones
//! ([`psdcal_model::Param`]), the channel gains (the points are then
//! recomputed from their amplitudes through the gains stage, docs/model.md
//! §1), or the parameters of any other stage. Poses are updated additively in
//! `(rvec, t)` ([`FitState::stepped`]).
//!
//! A [`Prior`] (a PSD map refined with its scan's information) adds one
//! residual group on the sensor parameters only, `s L (m − μ)`
//! ([`crate::prior`]). Under a noise model other than uniform each residual is
//! whitened by its point's weights ([`crate::weighting`]).

use nalgebra::{Matrix2, Matrix2x3, SMatrix, Vector2};
use psdcal_model::{ChainJacobian, CostKind, Model, ModelError, Pose};
use psdcal_solver::normal_equations::{ResidualTerm, Step};
use psdcal_solver::solver::{self, Problem, RobustLoss};

use crate::data::CalibrationData;
use crate::problem::prior::Prior;
use crate::problem::weighting::PointWeights;
use crate::CalibError;

/// One point's residual, `∂r/∂pose` and `∂r/∂m`.
pub(crate) type PointLinearization = (Vector2<f64>, SMatrix<f64, 2, 6>, Matrix2<f64>);

/// What the refinement estimates: the model and one pose per image.
#[derive(Debug, Clone, PartialEq)]
pub struct FitState {
    /// The model.
    pub model: Model,
    /// One `sensor_from_template` per image.
    pub poses: Vec<Pose>,
}

impl FitState {
    /// The state a solver's `step` leads to: the model's freed `columns`
    /// and each pose moved by their parts of it; `None` when the stepped
    /// model is not valid (the solver then rejects the step).
    pub fn stepped(&self, columns: &[usize], step: &Step) -> Option<FitState> {
        let model = self.model.stepped(columns, step.da.as_slice());
        model.validate().ok()?;
        let poses = self
            .poses
            .iter()
            .zip(&step.db)
            .map(|(pose, d)| pose.stepped(d.as_slice()))
            .collect();
        Some(FitState { model, poses })
    }
}

/// The calibration cost of a data set as a [`Problem`]: the model's freed
/// columns are the global block, each image's pose a block of six.
#[derive(Debug, Clone)]
pub struct CalibrationProblem<'a> {
    data: &'a CalibrationData,
    cost: CostKind,
    /// Flat model columns of the freed parameters, in order.
    columns: Vec<usize>,
    /// Position of each flat column among the freed ones.
    position: Vec<Option<usize>>,
    /// Recompute the points from the amplitudes through the gains stage.
    amplitudes: bool,
    weights: Option<&'a PointWeights>,
    prior: Option<PriorTerms<'a>>,
}

/// A prior attached to a problem: its model columns and, per parameter,
/// its slot among the freed ones (a fixed one only adds to the cost).
#[derive(Debug, Clone)]
struct PriorTerms<'a> {
    prior: &'a Prior,
    columns: Vec<usize>,
    slots: Vec<Option<usize>>,
    jacobian: nalgebra::DMatrix<f64>,
}

impl<'a> CalibrationProblem<'a> {
    /// The problem of `data` for `model` with the parameters `free` (names)
    /// freed; `weights` whiten the residuals.
    pub fn new(
        data: &'a CalibrationData,
        cost: CostKind,
        model: &Model,
        free: &[String],
        weights: Option<&'a PointWeights>,
    ) -> Result<Self, CalibError> {
        let mut columns = Vec::with_capacity(free.len());
        for name in free {
            let column = model.index(name).ok_or_else(|| CalibError::InvalidInput {
                reason: format!(
                    "cannot free '{name}': the model has no such parameter (it has {})",
                    model.names().join(", ")
                ),
            })?;
            if columns.contains(&column) {
                return Err(CalibError::Numerical {
                    stage: "refinement",
                    reason: format!("parameter {name} freed twice"),
                });
            }
            columns.push(column);
        }
        let mut position = vec![None; model.len()];
        for (k, c) in columns.iter().enumerate() {
            position[*c] = Some(k);
        }
        let amplitudes = model.gains_stage().is_some();
        if amplitudes && !data.has_amplitudes() {
            return Err(CalibError::InvalidInput {
                reason: "estimating the channel gains needs the electrode amplitudes of every point (signals.csv)".into(),
            });
        }
        Ok(Self {
            data,
            cost,
            columns,
            position,
            amplitudes,
            weights,
            prior: None,
        })
    }

    /// The problem with `prior`'s residuals added ([`crate::prior`]);
    /// its parameters must be the model's.
    pub fn with_prior(
        mut self,
        model: &Model,
        prior: Option<&'a Prior>,
    ) -> Result<Self, CalibError> {
        self.prior = match prior {
            None => None,
            Some(prior) => {
                let columns = prior.columns(model)?;
                let slots = columns.iter().map(|c| self.position[*c]).collect();
                Some(PriorTerms {
                    prior,
                    columns,
                    slots,
                    jacobian: prior.jacobian(),
                })
            }
        };
        Ok(self)
    }

    /// The attached prior.
    pub fn prior(&self) -> Option<&'a Prior> {
        self.prior.as_ref().map(|p| p.prior)
    }

    /// The prior's residuals at `state` (empty without a prior).
    pub fn prior_residuals(&self, state: &FitState) -> nalgebra::DVector<f64> {
        match &self.prior {
            None => nalgebra::DVector::zeros(0),
            Some(t) => {
                let values = state.model.values();
                let m = nalgebra::DVector::from_iterator(
                    t.columns.len(),
                    t.columns.iter().map(|c| values[*c]),
                );
                t.prior.residuals(&m)
            }
        }
    }

    /// A prior matrix over its parameters (`information` or `meat`)
    /// placed at their slots among the freed parameters (p × p; `None`
    /// without a prior).
    pub fn embed_prior(
        &self,
        matrix: impl Fn(&Prior) -> nalgebra::DMatrix<f64>,
    ) -> Option<nalgebra::DMatrix<f64>> {
        let t = self.prior.as_ref()?;
        let m = matrix(t.prior);
        let p = self.columns.len();
        let mut out = nalgebra::DMatrix::zeros(p, p);
        for (i, si) in t.slots.iter().enumerate() {
            for (j, sj) in t.slots.iter().enumerate() {
                if let (Some(a), Some(b)) = (si, sj) {
                    out[(*a, *b)] = m[(i, j)];
                }
            }
        }
        Some(out)
    }

    /// The flat model columns of the freed parameters.
    pub fn columns(&self) -> &[usize] {
        &self.columns
    }

    /// The data set.
    pub fn data(&self) -> &'a CalibrationData {
        self.data
    }

    /// A buffer for [`Self::linearize`] that computes the freed columns
    /// only.
    pub(crate) fn jacobian_buffer(&self, model: &Model) -> ChainJacobian {
        let mut jac = model.jacobian_buffer();
        jac.restrict_to(&self.columns);
        jac
    }

    fn point_error(&self, image: usize, k: usize, e: ModelError) -> CalibError {
        point_error(self.data, image, self.data.images[image].points[k].led, e)
    }

    /// The measured point of observation `k` of image `i` and, when it comes
    /// from the amplitudes through the gains stage, `∂m/∂gains`.
    pub fn measured(
        &self,
        model: &Model,
        i: usize,
        k: usize,
    ) -> Result<(Vector2<f64>, Option<Matrix2x3<f64>>), ModelError> {
        match (self.amplitudes, self.data.amplitudes.as_ref()) {
            (true, Some(amps)) => model
                .measured_from_amplitudes_with_jacobian(&amps[i][k])
                .map(|(m, j)| (m, Some(j))),
            _ => Ok((self.data.images[i].points[k].measured, None)),
        }
    }

    /// The (unweighted) residual of observation `k` of image `i`.
    pub fn residual(
        &self,
        state: &FitState,
        i: usize,
        k: usize,
    ) -> Result<Vector2<f64>, ModelError> {
        self.residual_using(state, i, k, &state.poses[i].rotation())
    }

    /// [`Self::residual`] with image `i`'s rotation matrix computed once.
    pub(crate) fn residual_using(
        &self,
        state: &FitState,
        i: usize,
        k: usize,
        rotation: &nalgebra::Matrix3<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        let obs = &self.data.images[i].points[k];
        let xy = self.data.template[obs.led];
        let (m, _) = self.measured(&state.model, i, k)?;
        let pose = &state.poses[i];
        Ok(match self.cost {
            CostKind::Template => state.model.back_project_using(rotation, &pose.t, &m)? - xy,
            CostKind::Image => state.model.project_near(pose, &xy, Some(&m))? - m,
        })
    }

    /// Residual, `∂r/∂θ_free` (2×p, column-major into `a`), `∂r/∂pose` and
    /// `∂r/∂m` (how noise on the measured point enters the residual: the
    /// back-projection's Jacobian for the template-plane cost, `−I` for the
    /// image plane), unweighted.
    pub(crate) fn linearize(
        &self,
        state: &FitState,
        i: usize,
        k: usize,
        rotation: &psdcal_model::RotationJacobian,
        jac: &mut ChainJacobian,
        a: &mut [f64],
    ) -> Result<PointLinearization, ModelError> {
        let obs = &self.data.images[i].points[k];
        let xy = self.data.template[obs.led];
        let (m, dm_dg) = self.measured(&state.model, i, k)?;
        let pose = &state.poses[i];
        // `gain_map`: how the measured point's gain Jacobian enters r.
        let (r, b, gain_map) = match self.cost {
            CostKind::Template => {
                let (p, j) = state
                    .model
                    .back_project_with_jacobians(pose, rotation, &m, jac)?;
                (p - xy, j.wrt_pose, j.wrt_point)
            }
            CostKind::Image => {
                let (p, j) =
                    state
                        .model
                        .project_with_jacobians_near(pose, rotation, &xy, Some(&m), jac)?;
                (p - m, j.wrt_pose, -Matrix2::identity())
            }
        };
        for (slot, c) in self.columns.iter().enumerate() {
            a[2 * slot] = jac.wrt_params[2 * c];
            a[2 * slot + 1] = jac.wrt_params[2 * c + 1];
        }
        if let (Some(g), Some(cols)) = (dm_dg, state.model.gain_columns()) {
            let dr_dg = gain_map * g;
            for (n, c) in cols.iter().enumerate() {
                if let Some(slot) = self.position[*c] {
                    a[2 * slot] += dr_dg[(0, n)];
                    a[2 * slot + 1] += dr_dg[(1, n)];
                }
            }
        }
        Ok((r, b, gain_map))
    }
}

impl Problem for CalibrationProblem<'_> {
    type State = FitState;
    type Error = CalibError;

    fn global_len(&self) -> usize {
        self.columns.len()
    }

    fn block_count(&self) -> usize {
        self.data.images.len()
    }

    fn evaluate(
        &self,
        state: &FitState,
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>),
    ) -> Result<(), CalibError> {
        let p = self.columns.len();
        let mut jac = self.jacobian_buffer(&state.model);
        let mut a = vec![0.0; 2 * p];
        for (i, image) in self.data.images.iter().enumerate() {
            let rotation = jacobians.then(|| state.poses[i].rotation_jacobian());
            let plain_rotation = state.poses[i].rotation();
            for k in 0..image.points.len() {
                let w = self.weights.map(|w| *w.get(i, k));
                if let Some(rotation) = &rotation {
                    let (mut r, mut b, _) = self
                        .linearize(state, i, k, rotation, &mut jac, &mut a)
                        .map_err(|e| self.point_error(i, k, e))?;
                    if let Some(w) = w {
                        r = w * r;
                        b = w * b;
                        for column in a.chunks_exact_mut(2) {
                            let v = w * Vector2::new(column[0], column[1]);
                            column.copy_from_slice(v.as_slice());
                        }
                    }
                    visit(&ResidualTerm {
                        r: r.as_slice(),
                        a: &a,
                        block: Some((i, b.as_slice())),
                    });
                } else {
                    let mut r = self
                        .residual_using(state, i, k, &plain_rotation)
                        .map_err(|e| self.point_error(i, k, e))?;
                    if let Some(w) = w {
                        r = w * r;
                    }
                    visit(&ResidualTerm {
                        r: r.as_slice(),
                        a: &[],
                        block: None,
                    });
                }
            }
        }
        if let Some(t) = &self.prior {
            // One row per prior residual: `s L (m − μ)`, `∂/∂m = s L`.
            let r = self.prior_residuals(state);
            let mut row = vec![0.0; if jacobians { p } else { 0 }];
            for (k, rk) in r.iter().enumerate() {
                if jacobians {
                    row.fill(0.0);
                    for (j, slot) in t.slots.iter().enumerate() {
                        if let Some(slot) = slot {
                            row[*slot] = t.jacobian[(k, j)];
                        }
                    }
                }
                visit(&ResidualTerm {
                    r: std::slice::from_ref(rk),
                    a: &row,
                    block: None,
                });
            }
        }
        Ok(())
    }

    fn apply_step(&self, state: &FitState, step: &Step) -> Option<FitState> {
        state.stepped(&self.columns, step)
    }
}

/// Names the image and LED of a point that cannot be evaluated.
pub(crate) fn point_error(
    data: &CalibrationData,
    image: usize,
    led: usize,
    e: ModelError,
) -> CalibError {
    CalibError::Numerical {
        stage: "refinement",
        reason: format!("image '{}', LED #{}: {e}", data.images[image].id, led + 1),
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
