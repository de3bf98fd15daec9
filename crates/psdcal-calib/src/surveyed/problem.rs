//! The image-plane cost of surveyed points as a problem for the one solver
//! (docs/model.md §8.4):
//!
//! ```text
//! r_ij = project(θ, pose_i, P_j) − m_ij    (mm on the sensor)
//! ```
//!
//! over the freed model parameters (the global block) and one
//! `sensor_from_template` pose per image (a block of six), with the same
//! stage-chain [`Model`] as the planar fit. Also the dense Jacobians at a
//! state — with respect to `x = (θ, poses)` and to the surveyed points —
//! that the survey-noise covariance ([`crate::surveyed::survey_covariance`])
//! is built from.

use nalgebra::{DMatrix, DVector, SMatrix, Vector2};
use psdcal_model::{Model, Param};
use psdcal_solver::normal_equations::{ResidualTerm, Step};
use psdcal_solver::solver::Problem;

use crate::surveyed::input::SurveyedData;
use crate::CalibError;

/// One point's residual, `∂r/∂pose` and `∂r/∂P`.
type PointLinearization = (Vector2<f64>, SMatrix<f64, 2, 6>, SMatrix<f64, 2, 3>);

/// `J`, the residuals, and per observation its point and `∂r/∂P`.
pub type DenseJacobians = (DMatrix<f64>, DVector<f64>, Vec<(usize, SMatrix<f64, 2, 3>)>);

/// The model's parameters and one pose per image: the planar fit's state.
pub type SurveyedState = crate::problem::calibration_problem::FitState;

/// The image-plane cost of surveyed points as a solver [`Problem`].
#[derive(Debug, Clone)]
pub struct SurveyedProblem<'a> {
    data: &'a SurveyedData,
    columns: Vec<usize>,
}

impl<'a> SurveyedProblem<'a> {
    /// The problem with the standard parameters `free` freed.
    pub fn new(data: &'a SurveyedData, model: &Model, free: &[Param]) -> Result<Self, CalibError> {
        let columns = free
            .iter()
            .map(|p| {
                model
                    .index(p.name())
                    .ok_or_else(|| CalibError::InvalidInput {
                        reason: format!("the model has no parameter '{}'", p.name()),
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { data, columns })
    }

    /// The data set.
    pub fn data(&self) -> &'a SurveyedData {
        self.data
    }

    /// The flat model columns of the freed parameters.
    pub fn columns(&self) -> &[usize] {
        &self.columns
    }

    /// Residual, `∂r/∂θ_free` (2 × p, column-major into `a`), `∂r/∂pose`
    /// and `∂r/∂P` of observation `k` of image `i`.
    fn linearize(
        &self,
        state: &SurveyedState,
        i: usize,
        k: usize,
        a: &mut [f64],
    ) -> Result<PointLinearization, CalibError> {
        let obs = &self.data.images[i].points[k];
        let pose = &state.poses[i];
        let mut jac = state.model.jacobian_buffer();
        let (m, j) = state
            .model
            .project_point_with_jacobians(
                pose,
                &pose.rotation_jacobian(),
                &self.data.points[obs.led],
                &mut jac,
            )
            .map_err(|e| self.point_error(i, obs.led, e))?;
        for (slot, c) in self.columns.iter().enumerate() {
            a[2 * slot] = jac.wrt_params[2 * c];
            a[2 * slot + 1] = jac.wrt_params[2 * c + 1];
        }
        Ok((m - obs.measured, j.wrt_pose, j.wrt_point))
    }

    fn point_error(&self, i: usize, led: usize, e: psdcal_model::ModelError) -> CalibError {
        CalibError::Numerical {
            stage: "surveyed refinement",
            reason: format!(
                "image '{}', point '{}': {e}",
                self.data.images[i].id,
                self.data.names.get(led).map_or("?", String::as_str)
            ),
        }
    }
}

impl Problem for SurveyedProblem<'_> {
    type State = SurveyedState;
    type Error = CalibError;

    fn global_len(&self) -> usize {
        self.columns.len()
    }

    fn block_count(&self) -> usize {
        self.data.images.len()
    }

    fn evaluate(
        &self,
        state: &SurveyedState,
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>),
    ) -> Result<(), CalibError> {
        let mut a = vec![0.0; 2 * self.columns.len()];
        for (i, image) in self.data.images.iter().enumerate() {
            for (k, obs) in image.points.iter().enumerate() {
                if jacobians {
                    let (r, b, _) = self.linearize(state, i, k, &mut a)?;
                    visit(&ResidualTerm {
                        r: r.as_slice(),
                        a: &a,
                        block: Some((i, b.as_slice())),
                    });
                } else {
                    let m = state
                        .model
                        .project_point(&state.poses[i], &self.data.points[obs.led])
                        .map_err(|e| self.point_error(i, obs.led, e))?;
                    let r = m - obs.measured;
                    visit(&ResidualTerm {
                        r: r.as_slice(),
                        a: &[],
                        block: None,
                    });
                }
            }
        }
        Ok(())
    }

    fn apply_step(&self, state: &SurveyedState, step: &Step) -> Option<SurveyedState> {
        state.stepped(&self.columns, step)
    }
}

/// The dense Jacobians at a state: `J` (2n × (p + 6 images)), the
/// residuals, and per observation its point index and `∂r/∂P` (2 × 3).
pub fn dense_jacobians(
    data: &SurveyedData,
    state: &SurveyedState,
    free: &[Param],
) -> Result<DenseJacobians, CalibError> {
    let problem = SurveyedProblem::new(data, &state.model, free)?;
    let p = free.len();
    let n_images = data.images.len();
    let rows: usize = data.images.iter().map(|i| 2 * i.points.len()).sum();
    let cols = p + 6 * n_images;
    let mut j = DMatrix::zeros(rows, cols);
    let mut r = DVector::zeros(rows);
    let mut jp = Vec::with_capacity(rows / 2);
    let mut a = vec![0.0; 2 * p];
    let mut row = 0;
    for (i, image) in data.images.iter().enumerate() {
        for k in 0..image.points.len() {
            let (res, b, dp) = problem.linearize(state, i, k, &mut a)?;
            for d in 0..2 {
                r[row + d] = res[d];
                for c in 0..p {
                    j[(row + d, c)] = a[2 * c + d];
                }
                for c in 0..6 {
                    j[(row + d, p + 6 * i + c)] = b[(d, c)];
                }
            }
            jp.push((image.points[k].led, dp));
            row += 2;
        }
    }
    Ok((j, r, jp))
}
