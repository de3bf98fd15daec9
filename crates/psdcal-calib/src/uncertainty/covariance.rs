//! Uncertainty of a calibration (docs/model.md §4.6): the covariance
//! `σ² (JᵀJ)⁻¹` of the estimated parameters at the solution, with
//! `σ² = cost / (2·points − parameters)` (`parameters` counts the freed
//! sensor parameters and 6 per pose). For a noise-weighted fit
//! ([`crate::weighting`]) `J` and `cost` are the whitened ones, so `σ²` is
//! the variance of a unit-weight coordinate and `σ² (JᵀJ)⁻¹` the
//! generalised-least-squares covariance.
//!
//! With a prior on some parameters ([`crate::prior`]: a PSD map refined
//! with its scan's information), `S = S_d + P` holds the data's information
//! `S_d` and the prior's `P = s² Σ⁻¹`; the estimate's covariance is the
//! sandwich `S⁻¹ (σ² S_d + s² P) S⁻¹` (the data's noise and the prior's own,
//! `s⁴ Σ⁻¹`; `σ² S⁻¹` when `s² = σ²`), the data's noise from the data's
//! cost alone with `dof = 2·points − parameters + tr(S⁻¹ P)` (the prior
//! determines `tr(S⁻¹ P)` of the parameters). For the sandwich method the
//! data's part is the sandwich below.
//!
//! `(JᵀJ)⁻¹` is never formed whole: the sensor-parameter block is the inverse
//! of the Schur complement `S⁻¹`, and each pose's 6 × 6 block is
//! `V_i⁻¹ + V_i⁻¹ W_iᵀ S⁻¹ W_i V_i⁻¹` ([`psdcal_solver::normal_equations`]).
//!
//! Identifiability: a parameter whose information is (nearly) explained by
//! the others has a huge variance inflation `S⁻¹_kk · S_kk`; such parameters,
//! and pairs whose correlation exceeds 0.98 in magnitude (p1/p2 with cx/cy,
//! k1 with l1 when the centres nearly coincide), are reported as warnings.

use nalgebra::{DMatrix, Matrix2, Matrix6, SMatrix};
use psdcal_model::ParameterCovariance;
use serde::Serialize;

use crate::data::CalibrationData;
use crate::problem::calibration_problem::{CalibrationProblem, FitState};
use crate::refine::linearization::AtSolution;
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::warning::FitWarning;
use crate::CalibError;
use psdcal_model::CostKind;
use psdcal_solver::normal_equations::NormalEquations;

use psdcal_model::stages::gains::GAIN_NAMES;

/// Correlation magnitude above which a pair of parameters is flagged.
pub const CORRELATION_WARNING: f64 = 0.98;
/// Variance inflation above which a parameter is flagged as poorly determined.
pub const INFLATION_WARNING: f64 = 1e4;

/// How a [`Covariance`] was estimated (calibration.json's `fit.uncertainty`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "method")]
pub enum CovarianceMethod {
    /// `σ² (JᵀJ)⁻¹`, one σ² for every residual coordinate: noise-weighted
    /// fits (whitened residuals), the image-plane cost and robust fits.
    Linear,
    /// The sandwich `σ_m² S⁻¹ (Σ Ãᵀ B Bᵀ Ã) S⁻¹` of the unweighted
    /// template-plane fit: isotropic point noise on the sensor propagated
    /// into the template plane through each point's back-projection
    /// (docs/model.md §4.6).
    Sandwich,
    /// The analytic covariance (linear or sandwich) with each parameter's σ
    /// raised to the jackknife over images when that is larger
    /// ([`crate::select::influence`]): `D C D` with
    /// `D = diag(max(1, σ_jackknife/σ_analytic))`.
    Jackknife,
    /// The sample covariance of refits on images resampled with
    /// replacement ([`crate::bootstrap`]).
    Bootstrap {
        /// Number of resamples.
        resamples: usize,
        /// Base seed: resample `b` draws from `ChaCha8Rng::seed_from_u64(seed + b)`.
        seed: u64,
    },
}

impl CovarianceMethod {
    /// The method's name: `linear`, `sandwich` or `bootstrap`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Linear => "linear",
            Self::Sandwich => "sandwich",
            Self::Jackknife => "jackknife",
            Self::Bootstrap { .. } => "bootstrap",
        }
    }
}

/// The covariance of a calibration's estimate: psdcal-model's
/// [`ParameterCovariance`] of the freed parameters (dereferenced to, for
/// `std`, `correlation`, `names`, …) with what only a fit has.
#[derive(Debug, Clone, PartialEq)]
pub struct Covariance {
    /// The freed parameters, in the order of [`RefineOptions::free_names`]
    /// (standard ones, gains, other stages'), and their covariance σ² S⁻¹
    /// in their units squared.
    pub parameters: ParameterCovariance,
    /// Per image, the 6 × 6 covariance of `(rvec, t)`.
    pub pose_blocks: Vec<Matrix6<f64>>,
    /// The residual variance σ² per coordinate (cost units: mm²; for the
    /// sandwich, the variance of the measured point per coordinate on the
    /// sensor, mm²).
    pub sigma2: f64,
    /// Degrees of freedom `2·points − parameters`.
    pub dof: usize,
    /// Identifiability warnings (empty when the data pin everything down).
    pub warnings: Vec<FitWarning>,
    /// How it was estimated.
    pub method: CovarianceMethod,
}

impl std::ops::Deref for Covariance {
    type Target = ParameterCovariance;
    fn deref(&self) -> &ParameterCovariance {
        &self.parameters
    }
}

impl Covariance {
    /// Standard deviations of the relative gains `(g_x2, g_y1, g_y2)`, when
    /// they were estimated.
    pub fn gain_std(&self) -> Option<[f64; 3]> {
        let sd = GAIN_NAMES.map(|n| self.std(n));
        sd.iter()
            .all(Option::is_some)
            .then(|| sd.map(|s| s.unwrap_or(0.0)))
    }
}

/// The analytic method [`covariance`] uses for a fit: the sandwich for the
/// unweighted template-plane cost without a robust loss (the default fit,
/// whose residuals are not equally noisy), [`CovarianceMethod::Linear`]
/// otherwise (whitened residuals, the image plane, robust weights).
pub fn analytic_method(refined: &Refined, options: &RefineOptions) -> CovarianceMethod {
    if options.cost == CostKind::Template && refined.weights.is_none() && options.robust.is_none() {
        CovarianceMethod::Sandwich
    } else {
        CovarianceMethod::Linear
    }
}

/// The covariance at a refinement's solution (its model, poses, cost and
/// point weights) for the cost and freed parameters of `options`, by
/// [`analytic_method`].
pub fn covariance(
    data: &CalibrationData,
    refined: &Refined,
    options: &RefineOptions,
) -> Result<Covariance, CalibError> {
    covariance_with(data, refined, options, analytic_method(refined, options))
}

/// The covariance by an analytic `method` (`Linear` or `Sandwich`; a
/// `Bootstrap` method is computed by [`crate::bootstrap`] and refused here).
pub fn covariance_with(
    data: &CalibrationData,
    refined: &Refined,
    options: &RefineOptions,
    method: CovarianceMethod,
) -> Result<Covariance, CalibError> {
    let at = AtSolution::new(data, refined, options)?;
    covariance_at(&at, data, refined, options, method)
}

/// [`covariance_with`] from the fit already linearised at its solution.
pub(crate) fn covariance_at(
    at: &AtSolution<'_>,
    data: &CalibrationData,
    refined: &Refined,
    options: &RefineOptions,
    method: CovarianceMethod,
) -> Result<Covariance, CalibError> {
    let names = options.free_names();
    let (problem, state, ne) = (&at.problem, &at.state, &at.ne);
    let (columns, poses, cost) = (problem.columns(), &refined.poses, refined.cost);
    let parameters = columns.len() + 6 * poses.len();
    let observations = 2 * data.point_count();
    let prior_rows = problem.prior().map_or(0, |p| p.len());
    if observations + prior_rows <= parameters {
        return Err(CalibError::Degenerate {
            reason: format!(
                "{observations} coordinates cannot determine {parameters} parameters; add images or LEDs"
            ),
        });
    }
    let (s_inv, pose_inv) = ne.inverse_blocks().ok_or_else(|| CalibError::Degenerate {
        reason: "the information matrix is singular: some freed parameter is not determined by the data \
                 (fix it, or add images that vary the template pose)"
            .into(),
    })?;
    // The prior's information P at the freed slots; the parameters it
    // determines, tr(S⁻¹ P); the data's cost without its residuals.
    let prior_info = problem.embed_prior(|p| p.information());
    let prior_share = prior_info
        .as_ref()
        .map_or(0.0, |p| (&s_inv * p).trace().clamp(0.0, parameters as f64));
    let data_cost = (cost - problem.prior_residuals(state).norm_squared()).max(0.0);
    let dof_real = observations as f64 - parameters as f64 + prior_share;
    if dof_real < 1.0 {
        return Err(CalibError::Degenerate {
            reason: format!(
                "{observations} coordinates leave no degrees of freedom for the noise beside \
                 {parameters} parameters ({prior_share:.1} of them held by the prior)"
            ),
        });
    }
    let dof = dof_real.round() as usize;
    let mut warnings = Vec::new();
    if let Some(s) = ne.schur_complement() {
        for (k, p) in names.iter().enumerate() {
            let inflation = s_inv[(k, k)] * s[(k, k)];
            if inflation > INFLATION_WARNING {
                warnings.push(FitWarning::PoorlyDetermined {
                    parameter: p.to_string(),
                    inflation,
                });
            }
        }
    }
    let (matrix, pose_blocks, sigma2) = match method {
        CovarianceMethod::Linear => {
            let sigma2 = data_cost / dof_real;
            let blocks = pose_inv.into_iter().map(|b| b * sigma2).collect();
            let matrix = match (&prior_info, problem.prior()) {
                // S⁻¹ (σ² (S − P) + s² P) S⁻¹.
                (Some(p), Some(prior)) => {
                    let s_full =
                        s_inv
                            .clone()
                            .try_inverse()
                            .ok_or_else(|| CalibError::Degenerate {
                                reason: "the information matrix is singular".into(),
                            })?;
                    let meat = (s_full - p) * sigma2 + p * prior.scale().powi(2);
                    &s_inv * meat * &s_inv
                }
                _ => s_inv * sigma2,
            };
            (matrix, blocks, sigma2)
        }
        CovarianceMethod::Sandwich => sandwich(problem, state, ne, &s_inv, dof_real)?,
        CovarianceMethod::Bootstrap { .. } | CovarianceMethod::Jackknife => {
            return Err(CalibError::InvalidInput {
                reason: "a bootstrap covariance comes from psdcal_calib::bootstrap".into(),
            })
        }
    };
    // The matrix is symmetric up to rounding: store it exactly symmetric.
    let matrix = (&matrix + matrix.transpose()) * 0.5;
    let estimated =
        ParameterCovariance::new(names.clone(), matrix).map_err(|e| CalibError::Numerical {
            stage: "covariance",
            reason: e.to_string(),
        })?;
    warnings.extend(correlation_warnings(&estimated));
    Ok(Covariance {
        parameters: estimated,
        pose_blocks,
        sigma2,
        dof,
        warnings,
        method,
    })
}

/// Warnings for pairs correlated beyond [`CORRELATION_WARNING`].
pub(crate) fn correlation_warnings(estimated: &ParameterCovariance) -> Vec<FitWarning> {
    let names = estimated.names();
    let corr = estimated.correlation();
    let mut warnings = Vec::new();
    for i in 0..names.len() {
        for j in (i + 1)..names.len() {
            if corr[(i, j)].abs() > CORRELATION_WARNING {
                warnings.push(FitWarning::StronglyCorrelated {
                    first: names[i].clone(),
                    second: names[j].clone(),
                    correlation: corr[(i, j)],
                });
            }
        }
    }
    warnings
}

/// One point's linearisation: `Ã = A − P V_i⁻¹ W_iᵀ` (2 × p, the sensor
/// Jacobian with the pose eliminated), `P = ∂r/∂pose` and `C̃ = B Bᵀ`
/// (the residual's covariance per unit of point variance).
struct PointTerm {
    p: SMatrix<f64, 2, 6>,
    c: Matrix2<f64>,
}

/// The sensor-parameter covariance, the pose blocks and `σ_m²`.
type Sandwich = (DMatrix<f64>, Vec<Matrix6<f64>>, f64);

/// The sandwich covariance of the unweighted template-plane estimate
/// (docs/model.md §4.6): with `B_j = ∂r_j/∂m_j`, `C̃_j = B_j B_jᵀ`,
/// `σ_m² = Σ r_jᵀ C̃_j⁻¹ r_j / dof`,
/// `Cov(θ) = σ_m² S⁻¹ (Σ Ã_jᵀ C̃_j Ã_j) S⁻¹`, and for pose `i`
/// `σ_m² V_i⁻¹ (W_iᵀ K W_i − W_iᵀ X_i − X_iᵀ W_i + Y_i) V_i⁻¹` with
/// `K = Σ g_j C̃_j g_jᵀ`, `g_j = S⁻¹ Ã_jᵀ`, `X_i = Σ_{j∈i} g_j C̃_j P_j`,
/// `Y_i = Σ_{j∈i} P_jᵀ C̃_j P_j`.
fn sandwich(
    problem: &CalibrationProblem<'_>,
    state: &FitState,
    ne: &NormalEquations,
    s_inv: &DMatrix<f64>,
    dof: f64,
) -> Result<Sandwich, CalibError> {
    let points = point_terms(problem, state, ne)?;
    let sigma2 = points.weighted_sum / dof;
    let (meat, sums) = meat_and_sums(problem, &points, sigma2);
    let k = s_inv * meat * s_inv;
    let mut blocks = Vec::with_capacity(points.images.len());
    for (i, (terms, u)) in points.images.iter().zip(&sums).enumerate() {
        let x = s_inv * u;
        let mut y = Matrix6::zeros();
        for t in terms {
            y += t.p.transpose() * t.c * t.p;
        }
        let w = &ne.w[i];
        let inner = w.transpose() * &k * w - w.transpose() * &x - x.transpose() * w;
        let inner = Matrix6::from_iterator(inner.iter().copied()) + y;
        blocks.push(points.v_inv[i] * inner * points.v_inv[i] * sigma2);
    }
    Ok((k * sigma2, blocks, sigma2))
}

/// Every point's linearisation for [`sandwich`], image after image.
struct PointTerms {
    /// Per image, its points' `P_j` and `C̃_j`.
    images: Vec<Vec<PointTerm>>,
    /// Every point's `Ã_j` (2 × p, column-major), one after the other.
    a_tilde: Vec<f64>,
    /// Per image, `V_i⁻¹`.
    v_inv: Vec<Matrix6<f64>>,
    /// `Σ r_jᵀ C̃_j⁻¹ r_j`.
    weighted_sum: f64,
}

/// Linearises every point at `state`: `Ã_j = A_j − P_j V_i⁻¹ W_iᵀ`, `P_j`,
/// `C̃_j = B_j B_jᵀ`, and the weighted sum of squares `Σ r_jᵀ C̃_j⁻¹ r_j`.
fn point_terms(
    problem: &CalibrationProblem<'_>,
    state: &FitState,
    ne: &NormalEquations,
) -> Result<PointTerms, CalibError> {
    let p = problem.columns().len();
    let data = problem.data();
    let mut jac = problem.jacobian_buffer(&state.model);
    let mut a = vec![0.0; 2 * p];
    let mut weighted_sum = 0.0;
    let mut images: Vec<Vec<PointTerm>> = Vec::with_capacity(data.images.len());
    // Every point's `Ã_j` (2 × p, column-major), one after the other.
    let mut a_tilde: Vec<f64> = Vec::with_capacity(2 * p * data.point_count());
    let singular = || CalibError::Degenerate {
        reason: "a pose is not determined by its image's points".into(),
    };
    let mut v_inv = Vec::with_capacity(data.images.len());
    for (i, image) in data.images.iter().enumerate() {
        let rotation = state.poses[i].rotation_jacobian();
        let vi = ne.v[i].cholesky().ok_or_else(singular)?.inverse();
        let wvt = (&ne.w[i] * vi).transpose(); // V_i⁻¹ W_iᵀ (6 × p)
        let mut terms = Vec::with_capacity(image.points.len());
        for k in 0..image.points.len() {
            let (r, pj, b) = problem
                .linearize(state, i, k, &rotation, &mut jac, &mut a)
                .map_err(|e| {
                    crate::problem::calibration_problem::point_error(
                        data,
                        i,
                        image.points[k].led,
                        e,
                    )
                })?;
            let c = b * b.transpose();
            let c_inv = c.try_inverse().ok_or_else(|| CalibError::Numerical {
                stage: "covariance",
                reason: format!(
                    "image '{}': a point's back-projection is singular",
                    image.id
                ),
            })?;
            weighted_sum += (r.transpose() * c_inv * r)[(0, 0)];
            // Ã = A − P V⁻¹ Wᵀ.
            for col in 0..p {
                for row in 0..2 {
                    let mut v = a[2 * col + row];
                    for q in 0..6 {
                        v -= pj[(row, q)] * wvt[(q, col)];
                    }
                    a_tilde.push(v);
                }
            }
            terms.push(PointTerm { p: pj, c });
        }
        images.push(terms);
        v_inv.push(vi);
    }
    Ok(PointTerms {
        images,
        a_tilde,
        v_inv,
        weighted_sum,
    })
}

/// The sandwich's meat `Σ Ãᵀ C̃ Ã` (in units of `σ_m²`, a prior's gradient
/// variance `s⁴ Σ⁻¹ = s² P` added) and, per image, `Σ_{j∈i} Ãᵀ C̃ P_j`.
fn meat_and_sums(
    problem: &CalibrationProblem<'_>,
    points: &PointTerms,
    sigma2: f64,
) -> (DMatrix<f64>, Vec<DMatrix<f64>>) {
    let p = problem.columns().len();
    let images = &points.images;
    // K = Σ g C̃ gᵀ with g = S⁻¹ Ãᵀ, i.e. S⁻¹ (Σ Ãᵀ C̃ Ã) S⁻¹; a prior's
    // gradient adds s⁴ Σ⁻¹ = s² P to the meat (in units of σ_m²). Per
    // image, X_i = S⁻¹ Σ_{j∈i} Ãᵀ C̃ P_j.
    let mut meat = match problem.prior() {
        Some(_) if sigma2 > 0.0 => problem
            .embed_prior(|q| q.meat())
            .map_or_else(|| DMatrix::zeros(p, p), |m| m / sigma2),
        _ => DMatrix::zeros(p, p),
    };
    let mut ac = vec![0.0; 2 * p]; // C̃ Ã (2 × p, column-major)
    let mut sums: Vec<DMatrix<f64>> = Vec::with_capacity(images.len());
    let mut a_tilde = points.a_tilde.chunks_exact(2 * p);
    for terms in images {
        let mut u = DMatrix::<f64>::zeros(p, 6); // Σ Ãᵀ C̃ P
        for t in terms {
            let at = a_tilde.next().expect("one Ã per point");
            for col in 0..p {
                let (x, y) = (at[2 * col], at[2 * col + 1]);
                ac[2 * col] = t.c[(0, 0)] * x + t.c[(0, 1)] * y;
                ac[2 * col + 1] = t.c[(1, 0)] * x + t.c[(1, 1)] * y;
            }
            for j in 0..p {
                for i in 0..p {
                    meat[(i, j)] += at[2 * i] * ac[2 * j] + at[2 * i + 1] * ac[2 * j + 1];
                }
            }
            let cp = t.c * t.p; // 2 × 6
            for q in 0..6 {
                for i in 0..p {
                    u[(i, q)] += at[2 * i] * cp[(0, q)] + at[2 * i + 1] * cp[(1, q)];
                }
            }
        }
        sums.push(u);
    }
    (meat, sums)
}
