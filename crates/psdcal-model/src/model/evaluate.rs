//! Evaluating a [`Model`]'s chain: measured → ideal → ray `(a, b)`, the
//! measured point from electrode amplitudes through the gains stage, and
//! the inverse ideal → measured (docs/model.md §8).
//!
//! Jacobians follow the chain rule: with `D_k = ∂p_k/∂p_{k−1}` and
//! `P_k = ∂p_k/∂θ_k`, `∂x/∂θ_k = D_K ⋯ D_{k+1} P_k` (accumulated backwards, added
//! into the flat columns of `θ_k`), `∂x/∂m = D_K ⋯ D_1`.
//!
//! The inverse (ideal → measured) is Newton's method on the 2×2 Jacobian with
//! step halving, to 1e-12 mm, with an optional polishing step; it fails
//! with a typed error where the map folds (`det ≤ 0`) or does not converge.

use nalgebra::{Matrix2, Unit, Vector2, Vector3};

use super::Model;
use crate::distortion::invert_newton_from;
use crate::stage::StageJacobian;
use crate::stages::{Gains, Pinhole};
use crate::ModelError;

/// Jacobians of one evaluation of the chain, with the scratch space the
/// evaluation needs (allocate once with [`Model::jacobian_buffer`], reuse per
/// point).
#[derive(Debug, Clone)]
pub struct ChainJacobian {
    /// `∂output/∂measured` (2×2).
    pub wrt_point: Matrix2<f64>,
    /// `∂output/∂θ` over the flat parameter vector (2×P, column-major).
    pub wrt_params: Vec<f64>,
    stage_input: Vec<Matrix2<f64>>,
    stage_params: Vec<Vec<f64>>,
    pinhole_params: [f64; 8],
    /// Per flat column, whether it is computed ([`Self::restrict_to`]).
    active: Vec<bool>,
}

impl ChainJacobian {
    /// Column `k` of `∂output/∂θ`.
    pub fn column(&self, k: usize) -> Vector2<f64> {
        Vector2::new(self.wrt_params[2 * k], self.wrt_params[2 * k + 1])
    }

    /// Computes only the flat columns `columns` of `∂output/∂θ` from now on
    /// (a fit's freed parameters); the others stay zero. Each column is its
    /// own chain of products, so those computed are the same to the bit.
    pub fn restrict_to(&mut self, columns: &[usize]) {
        self.active.iter_mut().for_each(|a| *a = false);
        for &c in columns {
            if let Some(a) = self.active.get_mut(c) {
                *a = true;
            }
        }
    }

    /// Multiplies every computed column of `∂output/∂θ` by `m` from the left.
    pub(crate) fn left_multiply(&mut self, m: &Matrix2<f64>) {
        for (column, _) in self
            .wrt_params
            .chunks_exact_mut(2)
            .zip(&self.active)
            .filter(|(_, a)| **a)
        {
            let v = m * Vector2::new(column[0], column[1]);
            column[0] = v.x;
            column[1] = v.y;
        }
    }
}

impl Model {
    /// A buffer for [`Self::ray_with_jacobians`] and
    /// [`Self::ideal_with_jacobians`].
    pub fn jacobian_buffer(&self) -> ChainJacobian {
        ChainJacobian {
            wrt_point: Matrix2::identity(),
            wrt_params: vec![0.0; 2 * self.len()],
            stage_input: vec![Matrix2::identity(); self.stages.len()],
            stage_params: self.blocks.iter().map(|b| vec![0.0; 2 * b.len()]).collect(),
            pinhole_params: [0.0; 8],
            active: vec![true; self.len()],
        }
    }

    /// The measured point of electrode amplitudes through the gains stage
    /// (the model must own the gains).
    pub fn measured_from_amplitudes(
        &self,
        amplitudes: &crate::Amplitudes,
    ) -> Result<Vector2<f64>, ModelError> {
        let (stage, cols) = self.gain_stage()?;
        stage.apply(&cols.map(|c| self.values[c]), amplitudes)
    }

    /// [`Self::measured_from_amplitudes`] with `∂m/∂(g_x2, g_y1, g_y2)`.
    pub fn measured_from_amplitudes_with_jacobian(
        &self,
        amplitudes: &crate::Amplitudes,
    ) -> Result<(Vector2<f64>, nalgebra::Matrix2x3<f64>), ModelError> {
        let (stage, cols) = self.gain_stage()?;
        stage.apply_with_jacobian(&cols.map(|c| self.values[c]), amplitudes)
    }

    fn gain_stage(&self) -> Result<(&Gains, [usize; 3]), ModelError> {
        match (&self.gains, self.gain_columns) {
            (Some(g), Some(c)) => Ok((g, c)),
            _ => Err(ModelError::InvalidModel {
                reason: "the model has no gains stage".into(),
            }),
        }
    }

    /// The ideal point of a measured point.
    pub fn ideal(&self, measured: &Vector2<f64>) -> Vector2<f64> {
        let mut p = *measured;
        for (stage, block) in self.stages.iter().zip(&self.blocks) {
            p = stage.apply(block, &p, None);
        }
        p
    }

    /// The normalised ray `(a, b)` of a measured point.
    pub fn ray(&self, measured: &Vector2<f64>) -> Vector2<f64> {
        Pinhole::eval(&self.pinhole_intrinsics(), &self.ideal(measured), None)
    }

    /// The normalised ray of an ideal point.
    pub fn ray_of_ideal(&self, ideal: &Vector2<f64>) -> Vector2<f64> {
        Pinhole::eval(&self.pinhole_intrinsics(), ideal, None)
    }

    /// The ideal point on the ray `(a, b, 1)`: `x = f a + γ b + cx`,
    /// `y = f b + cy` (P4).
    pub fn ideal_of_ray(&self, ab: &Vector2<f64>) -> Vector2<f64> {
        let k = self.pinhole_intrinsics();
        Vector2::new(k.f * ab.x + k.skew * ab.y + k.c.x, k.f * ab.y + k.c.y)
    }

    /// The ideal point with its Jacobians (written into `jac`).
    pub fn ideal_with_jacobians(
        &self,
        measured: &Vector2<f64>,
        jac: &mut ChainJacobian,
    ) -> Vector2<f64> {
        jac.wrt_params.iter_mut().for_each(|v| *v = 0.0);
        let mut p = *measured;
        for (k, (stage, block)) in self.stages.iter().zip(&self.blocks).enumerate() {
            let stage_jacobian = StageJacobian {
                wrt_input: &mut jac.stage_input[k],
                wrt_params: &mut jac.stage_params[k],
            };
            p = stage.apply(block, &p, Some(stage_jacobian));
        }
        let mut m = Matrix2::identity();
        for k in (0..self.stages.len()).rev() {
            let stage_params = &jac.stage_params[k];
            for (j, c) in self.columns[k].iter().enumerate() {
                if !jac.active[*c] {
                    continue;
                }
                let column = m * Vector2::new(stage_params[2 * j], stage_params[2 * j + 1]);
                jac.wrt_params[2 * c] += column.x;
                jac.wrt_params[2 * c + 1] += column.y;
            }
            m *= jac.stage_input[k];
        }
        jac.wrt_point = m;
        p
    }

    /// Unit direction, in the sensor frame, of the ray `(a, b, 1)` through a
    /// measured point.
    pub fn direction(&self, measured: &Vector2<f64>) -> Unit<Vector3<f64>> {
        let ab = self.ray(measured);
        Unit::new_normalize(Vector3::new(ab.x, ab.y, 1.0))
    }

    /// Unit direction, in the sensor frame, of the ray through an ideal point.
    pub fn direction_of_ideal(&self, ideal: &Vector2<f64>) -> Unit<Vector3<f64>> {
        let ab = self.ray_of_ideal(ideal);
        Unit::new_normalize(Vector3::new(ab.x, ab.y, 1.0))
    }

    /// The normalised ray with its Jacobians (written into `jac`).
    pub fn ray_with_jacobians(
        &self,
        measured: &Vector2<f64>,
        jac: &mut ChainJacobian,
    ) -> Vector2<f64> {
        let ideal = self.ideal_with_jacobians(measured, jac);
        self.ray_of_ideal_with_jacobians(&ideal, jac)
    }

    /// The pinhole applied to `ideal` with `jac` holding the ideal point's
    /// Jacobians ([`Self::ideal_with_jacobians`] at the same point): `jac`
    /// becomes the ray's (the second half of [`Self::ray_with_jacobians`], for
    /// callers that inspect the ideal point's Jacobians first).
    pub fn ray_of_ideal_with_jacobians(
        &self,
        ideal: &Vector2<f64>,
        jac: &mut ChainJacobian,
    ) -> Vector2<f64> {
        let mut dp = Matrix2::zeros();
        let ab = Pinhole::eval(
            &self.pinhole_intrinsics(),
            ideal,
            Some((&mut dp, &mut jac.pinhole_params)),
        );
        jac.left_multiply(&dp);
        for (j, c) in self.pinhole_columns.iter().enumerate() {
            if !jac.active[*c] {
                continue;
            }
            jac.wrt_params[2 * c] += jac.pinhole_params[2 * j];
            jac.wrt_params[2 * c + 1] += jac.pinhole_params[2 * j + 1];
        }
        jac.wrt_point = dp * jac.wrt_point;
        ab
    }

    /// `∂ideal/∂measured` at a point.
    pub fn ideal_point_jacobian(&self, measured: &Vector2<f64>) -> Matrix2<f64> {
        self.point_jacobian_with(measured, &mut Vec::new())
    }

    /// [`Self::ideal_point_jacobian`] with a reusable scratch buffer.
    pub(crate) fn point_jacobian_with(
        &self,
        measured: &Vector2<f64>,
        scratch: &mut Vec<f64>,
    ) -> Matrix2<f64> {
        let mut m = Matrix2::identity();
        let mut p = *measured;
        // ∂/∂θ is computed alongside and discarded: small blocks on the stack
        // (this runs in every Newton step of every projection), large ones in
        // the caller's scratch buffer.
        let mut small = [0.0; 32];
        for (stage, block) in self.stages.iter().zip(&self.blocks) {
            let mut d = Matrix2::identity();
            let scratch: &mut [f64] = if 2 * block.len() <= small.len() {
                &mut small[..2 * block.len()]
            } else {
                scratch.resize(2 * block.len(), 0.0);
                &mut scratch[..]
            };
            p = stage.apply(
                block,
                &p,
                Some(StageJacobian {
                    wrt_input: &mut d,
                    wrt_params: scratch,
                }),
            );
            m = d * m;
        }
        m
    }

    /// Whether `measured` lies in every stage's own domain (docs/model.md
    /// §8.3: a PSD map is known only on its scan's hull), following the
    /// point through the chain.
    pub fn in_domain(&self, measured: &Vector2<f64>) -> bool {
        if !self.has_domain() {
            return true;
        }
        let mut p = *measured;
        for (stage, block) in self.stages.iter().zip(&self.blocks) {
            if !stage.contains_input(&p) {
                return false;
            }
            p = stage.apply(block, &p, None);
        }
        true
    }

    /// The model's domain in measured coordinates when it is a convex
    /// polygon: the first stage's own ([`Stage::domain`](crate::stage::Stage::domain)),
    /// when no later stage limits its input. `None` when nothing limits the
    /// domain, or when a later stage does (its domain is then in that
    /// stage's input coordinates, known only through [`Self::in_domain`]).
    pub fn measured_domain(&self) -> Option<&crate::ConvexHull> {
        let (first, later) = self.stages.split_first()?;
        if later.iter().any(|s| s.has_domain()) {
            return None;
        }
        first.domain()
    }

    /// Whether some stage has a limited domain ([`Stage::has_domain`](crate::stage::Stage::has_domain)).
    pub fn has_domain(&self) -> bool {
        self.stages.iter().any(|s| s.has_domain())
    }

    /// Whether every distortion coefficient is zero (the chain is the
    /// identity up to the pinhole): checked through the stages' neutral
    /// values.
    pub(crate) fn distortion_is_identity(&self) -> bool {
        self.stages.iter().zip(&self.blocks).all(|(stage, block)| {
            stage
                .parameters()
                .iter()
                .zip(block)
                .all(|(p, v)| p.name == "cx" || p.name == "cy" || *v == p.neutral)
        })
    }

    /// The measured point whose ideal point is `ideal` (Newton, 1e-12 mm).
    pub fn measured_from_ideal(&self, ideal: &Vector2<f64>) -> Result<Vector2<f64>, ModelError> {
        self.measured_from_ideal_near(ideal, ideal)
    }

    /// The measured point whose ideal point is `ideal`, Newton stopped at
    /// the tolerance (1e-12 mm) without the polishing step of
    /// [`Self::measured_from_ideal`]: the inverse psdcal's simulators draw
    /// their true measured points with (their data sets were made with it;
    /// the two differ by less than the tolerance).
    pub fn measured_from_ideal_to_tolerance(
        &self,
        ideal: &Vector2<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        self.inverse(ideal, ideal, false)
    }

    /// [`Self::measured_from_ideal`] with Newton started at `near` (a point
    /// close to the answer, e.g. the measured point a prediction is compared
    /// with); the same answer to the inverse's tolerance.
    pub fn measured_from_ideal_near(
        &self,
        ideal: &Vector2<f64>,
        near: &Vector2<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        self.inverse(ideal, near, true)
    }

    fn inverse(
        &self,
        ideal: &Vector2<f64>,
        near: &Vector2<f64>,
        polish: bool,
    ) -> Result<Vector2<f64>, ModelError> {
        if !(ideal.x.is_finite() && ideal.y.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "ideal point",
            });
        }
        if self.distortion_is_identity() {
            return Ok(*ideal);
        }
        invert_newton_from(
            ideal,
            near,
            &|m| self.ideal(m),
            &|m| self.ideal_point_jacobian(m),
            polish,
        )
    }
}
