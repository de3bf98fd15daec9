//! Each image's influence on a fit, from the linearisation at its solution
//! (docs/model.md §4.8): what leaving one image out would do, without
//! refitting.
//!
//! With the poses eliminated, a point `j` of image `i` has the reduced
//! Jacobian `Ã_j = A_j − P_j V_i⁻¹ W_iᵀ` (`A = ∂r/∂θ`, `P = ∂r/∂pose`), and
//! the image's reduced information and score are
//!
//! ```text
//! S_i = Σ_{j∈i} Ã_jᵀ Ã_j,   g_i = Σ_{j∈i} Ã_jᵀ r_j,   S = Σ_i S_i,   Σ_i g_i = 0
//! ```
//!
//! (the last at the minimum). Leaving image `i` out removes its pose and its
//! terms; one Gauss–Newton step from the solution gives the leave-one-out
//! estimate
//!
//! ```text
//! θ₍₋ᵢ₎ − θ̂ = (S − S_i)⁻¹ g_i
//! ```
//!
//! and the left-out image, its pose refitted to its own points under
//! `θ₍₋ᵢ₎`, has the held-out residuals `e_j = r_j + Ã_j (θ₍₋ᵢ₎ − θ̂)` (the
//! refitted pose removes the part along `P_j`, and `Σ_j P_jᵀ r_j = 0` at the
//! solution). A held-out residual is turned into the angle between the
//! predicted and the measured ray: the measured point moves by
//! `δm = B_j⁻¹ e_j` (`B = ∂r/∂m`), the ray `(a, b, 1)` by `δ = J_ray δm`,
//! and the angle is `|u × (δ, 0)| / |u|²` with `u = (a, b, 1)`.
//!
//! The same steps give the jackknife over images (the uncertainty that
//! holds when residuals are correlated within an image,
//! [`crate::uncertainty::covariance`]).

use nalgebra::{DMatrix, DVector, Matrix2, Vector2};

use crate::data::CalibrationData;
use crate::problem::calibration_problem::point_error;
use crate::refine::linearization::AtSolution;
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::CalibError;

/// What each image does to the fit ([module documentation](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct ImageInfluence {
    /// Per image, `θ₍₋ᵢ₎ − θ̂` over the freed parameters (covariance order).
    pub delta: Vec<DVector<f64>>,
    /// Per image, each point's held-out angle error, rad.
    pub held_out_rad: Vec<Vec<f64>>,
}

impl ImageInfluence {
    /// The jackknife covariance over images,
    /// `(n − 1)/n Σ_i (δ_i − δ̄)(δ_i − δ̄)ᵀ`.
    pub fn jackknife(&self) -> DMatrix<f64> {
        let n = self.delta.len();
        let p = self.delta.first().map_or(0, |d| d.len());
        let mean = self.delta.iter().fold(DVector::zeros(p), |acc, d| acc + d) / n.max(1) as f64;
        let mut c = DMatrix::zeros(p, p);
        for d in &self.delta {
            let e = d - &mean;
            c += &e * e.transpose();
        }
        c * ((n as f64 - 1.0) / n.max(1) as f64)
    }

    /// Per image, the sum of its points' squared held-out angles, rad².
    pub fn image_sums(&self) -> Vec<f64> {
        self.held_out_rad
            .iter()
            .map(|a| a.iter().map(|x| x * x).sum())
            .collect()
    }

    /// The RMS held-out angle over every point, rad.
    pub fn rms_rad(&self) -> f64 {
        let count: usize = self.held_out_rad.iter().map(Vec::len).sum();
        (self.image_sums().iter().sum::<f64>() / count.max(1) as f64).sqrt()
    }
}

/// The influence of every image on the fit linearised in `at` (unweighted
/// residuals: the uniform noise model).
pub(crate) fn image_influence(at: &AtSolution<'_>) -> Result<ImageInfluence, CalibError> {
    let (problem, state, ne) = (&at.problem, &at.state, &at.ne);
    let p = problem.columns().len();
    let data = problem.data();
    let mut jac = problem.jacobian_buffer(&state.model);
    let mut ray_jac = problem.jacobian_buffer(&state.model);
    let mut a = vec![0.0; 2 * p];
    let singular = || CalibError::Degenerate {
        reason: "a pose is not determined by its image's points".into(),
    };
    // Per image: S_i, g_i and its points' (r, Ã, ∂ray/∂r, ray).
    struct PointRows {
        r: Vector2<f64>,
        to_ray: Matrix2<f64>,
        ray: Vector2<f64>,
    }
    let mut s_i = Vec::with_capacity(data.images.len());
    let mut g_i = Vec::with_capacity(data.images.len());
    let mut rows: Vec<Vec<PointRows>> = Vec::with_capacity(data.images.len());
    // Every point's Ã (2 × p, column-major), one after the other.
    let mut a_tildes: Vec<f64> = Vec::with_capacity(2 * p * data.point_count());
    let mut at = vec![0.0; 2 * p];
    for (i, image) in data.images.iter().enumerate() {
        let rotation = state.poses[i].rotation_jacobian();
        let vi = ne.v[i].cholesky().ok_or_else(singular)?.inverse();
        let wvt = (&ne.w[i] * vi).transpose(); // V_i⁻¹ W_iᵀ (6 × p)
        let mut s = DMatrix::zeros(p, p);
        let mut g = DVector::zeros(p);
        let mut points = Vec::with_capacity(image.points.len());
        for k in 0..image.points.len() {
            let (r, pj, b) = problem
                .linearize(state, i, k, &rotation, &mut jac, &mut a)
                .map_err(|e| point_error(data, i, image.points[k].led, e))?;
            // Ã = A − P V⁻¹ Wᵀ.
            for col in 0..p {
                for row in 0..2 {
                    let mut v = a[2 * col + row];
                    for q in 0..6 {
                        v -= pj[(row, q)] * wvt[(q, col)];
                    }
                    at[2 * col + row] = v;
                }
            }
            for j in 0..p {
                g[j] += at[2 * j] * r.x + at[2 * j + 1] * r.y;
                for l in j..p {
                    s[(j, l)] += at[2 * j] * at[2 * l] + at[2 * j + 1] * at[2 * l + 1];
                }
            }
            a_tildes.extend_from_slice(&at);
            let (m, _) = problem
                .measured(&state.model, i, k)
                .map_err(|e| point_error(data, i, image.points[k].led, e))?;
            let ray = state.model.ray_with_jacobians(&m, &mut ray_jac);
            let b_inv = b.try_inverse().ok_or_else(|| CalibError::Numerical {
                stage: "influence",
                reason: format!(
                    "image '{}': a point's residual does not depend on it",
                    image.id
                ),
            })?;
            points.push(PointRows {
                r,
                to_ray: ray_jac.wrt_point * b_inv,
                ray,
            });
        }
        s.fill_lower_triangle_with_upper_triangle();
        s_i.push(s);
        g_i.push(g);
        rows.push(points);
    }
    let s_total = s_i.iter().fold(DMatrix::zeros(p, p), |acc, s| acc + s);
    let mut delta = Vec::with_capacity(rows.len());
    let mut held_out_rad = Vec::with_capacity(rows.len());
    let mut a_tilde = a_tildes.chunks_exact(2 * p);
    for (i, points) in rows.iter().enumerate() {
        let d =
            solve_scaled(&(&s_total - &s_i[i]), &g_i[i]).ok_or_else(|| CalibError::Degenerate {
                reason: format!(
                    "without image '{}' the other images do not determine the freed parameters",
                    data.images[i].id
                ),
            })?;
        let angles = points
            .iter()
            .map(|pt| {
                let at = a_tilde.next().unwrap_or(&[]);
                let mut e = pt.r;
                for (col, dc) in d.iter().enumerate() {
                    e.x += at[2 * col] * dc;
                    e.y += at[2 * col + 1] * dc;
                }
                ray_angle(&pt.ray, &(pt.to_ray * e))
            })
            .collect();
        delta.push(d);
        held_out_rad.push(angles);
    }
    Ok(ImageInfluence {
        delta,
        held_out_rad,
    })
}

/// `M⁻¹ v` after Jacobi scaling (the columns span many orders of magnitude).
fn solve_scaled(m: &DMatrix<f64>, v: &DVector<f64>) -> Option<DVector<f64>> {
    let d = DVector::from_iterator(m.nrows(), m.diagonal().iter().map(|x| 1.0 / x.abs().sqrt()));
    if d.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let scaled = DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)] * d[i] * d[j]);
    let rhs = v.component_mul(&d);
    let x = scaled.cholesky()?.solve(&rhs);
    Some(x.component_mul(&d))
}

/// The angle between the ray `(a, b, 1)` and the ray moved by `δ`, to first
/// order: `|u × (δ, 0)| / |u|²`.
fn ray_angle(ray: &Vector2<f64>, delta: &Vector2<f64>) -> f64 {
    let (a, b) = (ray.x, ray.y);
    let cross = nalgebra::Vector3::new(-delta.y, delta.x, a * delta.y - b * delta.x);
    cross.norm() / (1.0 + a * a + b * b)
}

/// The analytic covariance `analytic` with each σ raised to the jackknife
/// over images of the fit linearised in `at` when that is larger:
/// `D C D`, `D = diag(max(1, σ_jackknife/σ_analytic))`; the correlations
/// stay the analytic ones. Returns the matrix.
pub(crate) fn jackknife_raised(
    at: &AtSolution<'_>,
    analytic: &DMatrix<f64>,
) -> Result<DMatrix<f64>, CalibError> {
    let jack = image_influence(at)?.jackknife();
    let p = analytic.nrows();
    let d: Vec<f64> = (0..p)
        .map(|k| {
            let ratio = (jack[(k, k)] / analytic[(k, k)]).sqrt();
            if ratio.is_finite() {
                ratio.max(1.0)
            } else {
                1.0
            }
        })
        .collect();
    Ok(DMatrix::from_fn(p, p, |i, j| {
        analytic[(i, j)] * d[i] * d[j]
    }))
}

/// Each image's influence on the fit `refined` of `data` under `options`
/// (freed parameters and cost), from the linearisation at its solution
/// ([module documentation](self)).
pub fn influence(
    data: &CalibrationData,
    refined: &Refined,
    options: &RefineOptions,
) -> Result<ImageInfluence, CalibError> {
    image_influence(&AtSolution::new(data, refined, options)?)
}
