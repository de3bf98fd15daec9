//! Uncertainty of a ray from the calibration's covariance and from the
//! measurement noise (first-order propagation, docs/model.md §5 with §4.6).
//!
//! With `θ̂` the estimated quantities — any of the model's named parameters
//! (`Model::names`: `Param::ALL`, the relative gains `g_x2, g_y1, g_y2` when a
//! calibration estimated them, another stage's coefficients) — and `Σ_θ`
//! their covariance ([`ParameterCovariance`], psdcal-model's one covariance
//! type, names resolved with `Model::index`):
//!
//! ```text
//! Σ_ab,cal  = J_θ Σ_θ J_θᵀ           J_θ = ∂(a, b)/∂θ̂  (gain columns: ∂(a,b)/∂m · ∂m/∂g)
//! Σ_ab,meas = σ_m² J_m J_mᵀ          J_m = ∂(a, b)/∂m, σ_m the point noise per coordinate, mm
//! Σ_α       = D (Σ_ab,cal + Σ_ab,meas) D,   D = ∂α/∂(a, b) = diag(1/(1+a²), 1/(1+b²))
//! ```
//!
//! This is the linearisation of the uncertainty behind the paper's
//! sensitivity analysis (P40)–(P42): instead of worst-case bounds per
//! parameter, the full covariance with its correlations. `(a, b)` are
//! dimensionless, angles in radians; `Σ` in their units squared.

use nalgebra::{DMatrix, Matrix2};
use psdcal_model::Model;

use crate::error::LocateError;

pub use psdcal_model::covariance::{CovarianceError, ParameterCovariance};

impl From<CovarianceError> for LocateError {
    fn from(e: CovarianceError) -> Self {
        LocateError::InvalidCovariance {
            reason: e.to_string(),
        }
    }
}

/// `J Σ Jᵀ` for a 2-vector whose Jacobian with respect to `model`'s flat
/// parameter vector is `wrt_params` (2 × `model.len()`, columns in the order
/// of [`Model::names`]). Each name of the covariance is resolved with
/// [`Model::index`], so a covariance over any parameter of the chain (the
/// standard ones, the gains, another stage's coefficients) propagates; a name
/// the model does not have is an [`LocateError::InvalidCovariance`].
///
/// ```
/// use nalgebra::{DMatrix, Matrix2};
/// use psdcal_locate::uncertainty::{propagate, ParameterCovariance};
/// use psdcal_model::{Model, SensorModel};
///
/// let model = Model::standard(&SensorModel::pinhole(8.0, 0.0, 0.0));
/// let cov = ParameterCovariance::from_named(&["cx"], &[vec![1e-4]]).unwrap();
/// // ∂a/∂cx = −1/f at the centre.
/// let mut j = DMatrix::zeros(2, model.len());
/// j[(0, model.index("cx").unwrap())] = -1.0 / 8.0;
/// let c = propagate(&cov, &model, &j).unwrap();
/// assert!((c[(0, 0)] - 1e-4 / 64.0).abs() < 1e-20);
/// let zoom = ParameterCovariance::from_named(&["zoom"], &[vec![1.0]]).unwrap();
/// assert!(propagate(&zoom, &model, &j).is_err());
/// ```
pub fn propagate(
    covariance: &ParameterCovariance,
    model: &Model,
    wrt_params: &DMatrix<f64>,
) -> Result<Matrix2<f64>, LocateError> {
    if covariance.is_empty() {
        return Ok(Matrix2::zeros());
    }
    if wrt_params.nrows() != 2 || wrt_params.ncols() != model.len() {
        return Err(LocateError::InvalidInput {
            what: "Jacobian",
            reason: format!(
                "{} x {}; expected 2 x {} (the model's parameters)",
                wrt_params.nrows(),
                wrt_params.ncols(),
                model.len()
            ),
        });
    }
    let columns = covariance_columns(covariance, model)?;
    let out = covariance.propagate_columns(wrt_params, &columns);
    Ok(Matrix2::new(
        out[(0, 0)],
        out[(0, 1)],
        out[(1, 0)],
        out[(1, 1)],
    ))
}

/// The column of `model` of each of `covariance`'s names (what
/// [`propagate`] maps them by); an unknown name is `InvalidCovariance`.
pub(crate) fn covariance_columns(
    covariance: &ParameterCovariance,
    model: &Model,
) -> Result<Vec<Option<usize>>, LocateError> {
    covariance
        .names()
        .iter()
        .map(|name| {
            model
                .index(name)
                .map(Some)
                .ok_or_else(|| LocateError::InvalidCovariance {
                    reason: format!(
                        "the sensor's model has no parameter '{name}' (it has {})",
                        model.names().join(", ")
                    ),
                })
        })
        .collect()
}

/// `σ² J Jᵀ`: the covariance of a 2-vector with Jacobian `j` with respect to
/// a point with independent noise of standard deviation `sigma` per
/// coordinate.
pub fn point_noise_covariance(j: &Matrix2<f64>, sigma: f64) -> Matrix2<f64> {
    j * j.transpose() * (sigma * sigma)
}

/// `(σx, σy, ρ)` of a 2×2 covariance: the standard deviations and the
/// correlation (0 when a σ is 0).
pub fn sigmas_and_correlation(cov: &Matrix2<f64>) -> (f64, f64, f64) {
    let sx = cov[(0, 0)].max(0.0).sqrt();
    let sy = cov[(1, 1)].max(0.0).sqrt();
    let rho = if sx > 0.0 && sy > 0.0 {
        (cov[(0, 1)] / (sx * sy)).clamp(-1.0, 1.0)
    } else {
        0.0
    };
    (sx, sy, rho)
}
