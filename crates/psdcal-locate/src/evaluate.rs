//! Positioning evaluation by the standard metrics (ISO/IEC 18305; the
//! IPIN/EvAAL competitions): how far estimates are from the truth, and
//! whether their error bars are honest.
//!
//! For `n` pairs (truth `t_i`, estimate `p_i`) the error is `e_i = p_i − t_i`
//! and its size `d_i = |e_i|`. Reported: `n`; the mean `Σ d_i / n`; the
//! median, 75th (the EvAAL score) and 95th percentiles of `d`; the RMS
//! `√(Σ d_i² / n)`; the maximum; the per-axis bias `Σ e_i / n`. For positions
//! also CE95, the 95th percentile of the horizontal error `√(e_x² + e_y²)`,
//! and SE95, the 95th percentile of the 3-D error (the `p95` of `d`).
//!
//! **Percentiles** interpolate linearly between order statistics (Hyndman
//! and Fan's definition 7, the default of NumPy and R): with the sizes
//! sorted `d_(0) ≤ … ≤ d_(n−1)`, the `q`-quantile is at rank `h = (n − 1) q`,
//! `d_(⌊h⌋) + (h − ⌊h⌋) (d_(⌊h⌋+1) − d_(⌊h⌋))`. The median is `q = 0.5`.
//!
//! **Honest error bars**: when an estimate carries a covariance `Σ_i`, the
//! truth lies inside its 95 % ellipsoid when the squared Mahalanobis
//! distance `e_iᵀ Σ_i⁻¹ e_i` is at most the χ² quantile of 0.95 with as many
//! degrees of freedom as dimensions ([`CHI2_95_3D`] for positions,
//! [`CHI2_95_2D`] for the two angles). With a correct covariance and
//! Gaussian errors the fraction inside is 0.95 up to sampling
//! (`±2√(0.95·0.05/n)`). Angles: the error of `(αx, αy)` in radians, its
//! size `√(Δαx² + Δαy²)`.
//!
//! **Failures** (emitters the system did not locate) are not dropped
//! silently: [`with_failures`] counts them. With `n` located and `k` failed
//! of `N = n + k` attempted, the success rate (availability) is `n / N`,
//! and the failure-inclusive percentiles are those of the `N` sizes with
//! every failure an error of `+∞` (as the EvAAL/IPIN rules score a missing
//! estimate by a penalty larger than any error): the same definition 7 over
//! `N` values, `+∞` as soon as the interpolation touches a failure
//! (`None`: the percentile is not reached). Mean, RMS, bias and the
//! ellipsoid fraction remain over the located pairs (an infinite error has
//! no mean), and are reported next to the success rate.

use nalgebra::{SMatrix, SVector, Vector2, Vector3};

use crate::error::LocateError;

/// χ²₃ quantile of 0.95 (`P(χ²₃ ≤ q) = 0.95`): the 95 % ellipsoid in 3-D.
pub const CHI2_95_3D: f64 = 7.814_727_903_251_178;
/// χ²₂ quantile of 0.95, `−2 ln 0.05`: the 95 % ellipse in 2-D.
pub const CHI2_95_2D: f64 = 5.991_464_547_107_979;

/// The error statistics of one kind of quantity (positions in mm or angles
/// in rad), as the module documentation defines them.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorStats {
    /// Pairs compared.
    pub n: usize,
    /// Mean error size.
    pub mean: f64,
    /// Median error size.
    pub median: f64,
    /// RMS error size.
    pub rms: f64,
    /// 75th percentile of the error size.
    pub p75: f64,
    /// 95th percentile of the error size.
    pub p95: f64,
    /// Largest error size.
    pub max: f64,
    /// Mean error per axis (estimate − truth).
    pub bias: Vec<f64>,
    /// Fraction of truths inside the estimate's 95 % covariance region
    /// (`None` when an estimate has no covariance).
    pub within_95: Option<f64>,
}

/// An estimated position against the truth, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PositionPair {
    /// The true position.
    pub truth: Vector3<f64>,
    /// The estimate.
    pub estimate: Vector3<f64>,
    /// The estimate's covariance, mm².
    pub covariance: Option<nalgebra::Matrix3<f64>>,
}

/// Estimated angles of arrival `(αx, αy)` against the truth, rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnglePair {
    /// The true angles.
    pub truth: Vector2<f64>,
    /// The estimate.
    pub estimate: Vector2<f64>,
    /// The estimate's covariance, rad².
    pub covariance: Option<nalgebra::Matrix2<f64>>,
}

/// The evaluation of positions.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionEvaluation {
    /// Statistics of the 3-D error, mm (`within_95`: the 95 % ellipsoid).
    pub stats: ErrorStats,
    /// CE95: 95th percentile of the horizontal (x–y) error, mm.
    pub ce95: f64,
    /// SE95: 95th percentile of the 3-D error, mm (equal to `stats.p95`).
    pub se95: f64,
    /// Each pair's error `estimate − truth`, mm, in the pairs' order.
    pub errors: Vec<Vector3<f64>>,
}

/// The evaluation of angles of arrival.
#[derive(Debug, Clone, PartialEq)]
pub struct AngleEvaluation {
    /// Statistics of the angle error, rad (`within_95`: the 95 % ellipse).
    pub stats: ErrorStats,
    /// Each pair's error `estimate − truth`, rad.
    pub errors: Vec<Vector2<f64>>,
}

/// The `q`-quantile (`0 ≤ q ≤ 1`) of values sorted ascending, by linear
/// interpolation between order statistics (module documentation); `None`
/// for no values.
pub fn percentile(sorted: &[f64], q: f64) -> Option<f64> {
    let n = sorted.len();
    if n == 0 || !(0.0..=1.0).contains(&q) {
        return None;
    }
    let h = (n - 1) as f64 * q;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(n - 1);
    Some(sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo]))
}

/// The `q`-quantile (definition 7) of `sorted` (finite, ascending) followed
/// by `failures` values of `+∞`: `None` when the interpolation reaches a
/// failure (the percentile is infinite) or there is no value at all.
pub fn percentile_with_failures(sorted: &[f64], failures: usize, q: f64) -> Option<f64> {
    let finite = sorted.len();
    let n = finite + failures;
    if n == 0 || !(0.0..=1.0).contains(&q) {
        return None;
    }
    let h = (n - 1) as f64 * q;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(n - 1);
    let frac = h - lo as f64;
    if lo >= finite || (hi >= finite && frac > 0.0) {
        return None;
    }
    let upper = if hi < finite { sorted[hi] } else { sorted[lo] };
    Some(sorted[lo] + frac * (upper - sorted[lo]))
}

/// Statistics that count the emitters not located (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct FailureStats {
    /// Emitters attempted: located and failed.
    pub attempted: usize,
    /// Emitters not located.
    pub failures: usize,
    /// Located / attempted (the availability).
    pub success_rate: f64,
    /// Median error with failures as `+∞` (`None`: infinite).
    pub median: Option<f64>,
    /// 75th percentile (the EvAAL score) with failures as `+∞`.
    pub p75: Option<f64>,
    /// 95th percentile with failures as `+∞`.
    pub p95: Option<f64>,
}

/// The failure-aware statistics of the located error sizes `sizes` (any
/// order, finite) and `failures` emitters not located; `None` when nothing
/// was attempted.
pub fn with_failures(sizes: &[f64], failures: usize) -> Option<FailureStats> {
    let attempted = sizes.len() + failures;
    if attempted == 0 {
        return None;
    }
    let mut sorted = sizes.to_vec();
    sorted.sort_by(f64::total_cmp);
    let q = |p: f64| percentile_with_failures(&sorted, failures, p);
    Some(FailureStats {
        attempted,
        failures,
        success_rate: sizes.len() as f64 / attempted as f64,
        median: q(0.5),
        p75: q(0.75),
        p95: q(0.95),
    })
}

/// Whether `e` lies inside the 95 % region of `cov` (`eᵀ Σ⁻¹ e ≤ q`),
/// solved by Cholesky; a covariance that is not positive definite is an
/// error naming pair `index`.
fn inside<const N: usize>(
    e: &SVector<f64, N>,
    cov: &SMatrix<f64, N, N>,
    quantile: f64,
    index: usize,
) -> Result<bool, LocateError> {
    let chol = cov
        .iter()
        .all(|v| v.is_finite())
        .then(|| cov.cholesky())
        .flatten()
        .ok_or_else(|| LocateError::InvalidCovariance {
            reason: format!("the covariance of pair {index} is not positive definite"),
        })?;
    let d2 = e.dot(&chol.solve(e));
    Ok(d2 <= quantile)
}

fn stats<const N: usize>(
    truths: impl Iterator<Item = SVector<f64, N>>,
    estimates: impl Iterator<Item = SVector<f64, N>>,
    covariances: &[Option<SMatrix<f64, N, N>>],
    quantile: f64,
) -> Result<(ErrorStats, Vec<SVector<f64, N>>), LocateError> {
    let errors: Vec<SVector<f64, N>> = truths.zip(estimates).map(|(t, p)| p - t).collect();
    let n = errors.len();
    if n == 0 {
        return Err(LocateError::InvalidInput {
            what: "evaluation",
            reason: "no estimate to compare with the truth; expected at least one".into(),
        });
    }
    if errors.iter().any(|e| !e.iter().all(|v| v.is_finite())) {
        return Err(LocateError::NonFinite {
            what: "evaluated position or angle",
        });
    }
    let mut sizes: Vec<f64> = errors.iter().map(|e| e.norm()).collect();
    sizes.sort_by(f64::total_cmp);
    let nf = n as f64;
    let q = |p: f64| percentile(&sizes, p).unwrap_or(0.0);
    let bias = errors.iter().fold(SVector::<f64, N>::zeros(), |a, e| a + e) / nf;
    let within_95 = if covariances.iter().all(Option::is_some) {
        let mut inside_count = 0usize;
        for (i, (e, c)) in errors.iter().zip(covariances).enumerate() {
            if let Some(c) = c {
                inside_count += usize::from(inside(e, c, quantile, i)?);
            }
        }
        Some(inside_count as f64 / nf)
    } else {
        None
    };
    Ok((
        ErrorStats {
            n,
            mean: sizes.iter().sum::<f64>() / nf,
            median: q(0.5),
            rms: (sizes.iter().map(|d| d * d).sum::<f64>() / nf).sqrt(),
            p75: q(0.75),
            p95: q(0.95),
            max: sizes[n - 1],
            bias: bias.iter().copied().collect(),
            within_95,
        },
        errors,
    ))
}

/// Evaluates estimated positions against the truth (module documentation).
/// `within_95` is given when every pair has a covariance. Errors: no pair,
/// a non-finite value, a covariance that is not positive definite.
pub fn evaluate_positions(pairs: &[PositionPair]) -> Result<PositionEvaluation, LocateError> {
    let covariances: Vec<_> = pairs.iter().map(|p| p.covariance).collect();
    let (stats, errors) = stats(
        pairs.iter().map(|p| p.truth),
        pairs.iter().map(|p| p.estimate),
        &covariances,
        CHI2_95_3D,
    )?;
    let mut horizontal: Vec<f64> = errors.iter().map(|e| e.x.hypot(e.y)).collect();
    horizontal.sort_by(f64::total_cmp);
    Ok(PositionEvaluation {
        ce95: percentile(&horizontal, 0.95).unwrap_or(0.0),
        se95: stats.p95,
        stats,
        errors,
    })
}

/// Evaluates estimated angles of arrival against the truth (module
/// documentation; `within_95` uses the 95 % ellipse).
pub fn evaluate_angles(pairs: &[AnglePair]) -> Result<AngleEvaluation, LocateError> {
    let covariances: Vec<_> = pairs.iter().map(|p| p.covariance).collect();
    let (stats, errors) = stats(
        pairs.iter().map(|p| p.truth),
        pairs.iter().map(|p| p.estimate),
        &covariances,
        CHI2_95_2D,
    )?;
    Ok(AngleEvaluation { stats, errors })
}
