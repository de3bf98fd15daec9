//! The map from a scan (docs/model.md §8.3): candidates, robust rejection,
//! cross-validated choice, the final fit and its covariance.
//!
//! 1. The frame is the measured points' bounding box, the domain their
//!    convex hull.
//! 2. A robust reference fit (the requested model, or for `auto` the
//!    largest square spline with at most `n/4` coefficients per axis) is
//!    reweighted with Huber weights; points beyond 5σ̂ are rejected
//!    ([`crate::robust`]).
//! 3. Each candidate is cross-validated on the kept points
//!    ([`crate::cross_validation`]) and one is chosen.
//! 4. The chosen model is fitted to the kept points. With `H = M⁻¹AᵀA` its
//!    effective number of coefficients is `tr H` and the noise per axis
//!    `σ² = Σ r²/(n − tr H)`; the coefficients' covariance is `σ_x² U` for
//!    `a_x` and `σ_y² U` for `a_y` (no cross terms), `U = M⁻¹ AᵀA M⁻¹` (the
//!    penalty's sandwich; `(AᵀA)⁻¹` without one).
//! 5. The map's own error at the scan points, `√mean(φᵀUφ (σ_x² + σ_y²))`,
//!    is reported beside the scan's noise `√(σ_x² + σ_y²)`.

use nalgebra::{DMatrix, DVector, Vector2};
use psdcal_model::stages::{MapBasis, MapFrame, PsdMap};
use psdcal_model::{ConvexHull, ParameterCovariance, Stage};

use crate::cross_validation::{choose, cross_validate, fold_of_points, CandidateScore};
use crate::error::PsdMapError;
use crate::normal::accumulate;
use crate::penalty::penalty;
use crate::robust::{huber_weights, robust_sigma, MAX_PASSES, REJECT_SIGMAS};
use crate::solve::{residuals, solve};

/// Polynomial orders `auto` tries.
pub const AUTO_POLY_ORDERS: std::ops::RangeInclusive<usize> = 1..=8;
/// Spline grids (cells per axis) `auto` tries.
pub const AUTO_SPLINE_CELLS: [usize; 9] = [1, 2, 3, 4, 5, 6, 8, 10, 12];
/// Folds of the cross-validation.
pub const DEFAULT_FOLDS: usize = 5;

/// Which model to fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelChoice {
    /// Chosen by cross-validation among [`AUTO_POLY_ORDERS`] and
    /// [`AUTO_SPLINE_CELLS`].
    Auto,
    /// This one.
    Fixed(MapBasis),
}

/// Options of [`fit_psd_map`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// The model.
    pub model: ModelChoice,
    /// Folds of the cross-validation (≥ 2).
    pub folds: usize,
    /// Seed of the fold assignment.
    pub seed: u64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            model: ModelChoice::Auto,
            folds: DEFAULT_FOLDS,
            seed: 0,
        }
    }
}

/// A candidate's result, for reports.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidateResult {
    /// The model.
    pub basis: MapBasis,
    /// Cross-validated RMS error, mm.
    pub cv_rms_mm: f64,
}

/// A fitted map.
#[derive(Debug, Clone)]
pub struct PsdMapFit {
    /// The stage (basis, frame, hull).
    pub map: PsdMap,
    /// Its block `(a_x, a_y)`, mm.
    pub block: Vec<f64>,
    /// `U` (K×K): the coefficients' covariance per unit noise variance.
    pub unit_covariance: DMatrix<f64>,
    /// Noise per axis `(σ_x, σ_y)` of the scan, mm.
    pub sigma_mm: Vector2<f64>,
    /// Cross-validated RMS error of the chosen model, mm.
    pub cv_rms_mm: f64,
    /// RMS residual of the final fit over the kept points, mm.
    pub rms_mm: f64,
    /// RMS standard error of the map at the scan points, mm.
    pub map_sigma_mm: f64,
    /// Effective number of coefficients per axis (`tr H`).
    pub effective_terms: f64,
    /// Residual `d_i − map(m_i)` of every scan point (rejected ones too), mm.
    pub residuals: Vec<Vector2<f64>>,
    /// Indices of the rejected points.
    pub rejected: Vec<usize>,
    /// Every candidate tried, with its score.
    pub candidates: Vec<CandidateResult>,
}

impl PsdMapFit {
    /// The block's covariance by the stage's parameter names.
    pub fn covariance(&self) -> ParameterCovariance {
        let k = self.map.terms();
        let mut m = DMatrix::zeros(2 * k, 2 * k);
        let (vx, vy) = (self.sigma_mm.x.powi(2), self.sigma_mm.y.powi(2));
        m.view_mut((0, 0), (k, k))
            .copy_from(&(&self.unit_covariance * vx));
        m.view_mut((k, k), (k, k))
            .copy_from(&(&self.unit_covariance * vy));
        let names = self
            .map
            .parameters()
            .iter()
            .map(|p| p.name.clone())
            .collect();
        // U is symmetric positive semi-definite by construction.
        ParameterCovariance::new(names, (&m + m.transpose()) * 0.5)
            .unwrap_or_else(|_| ParameterCovariance::none())
    }
}

/// The fewest points a model needs in a fit: a polynomial more than its
/// coefficients, a spline (whose penalty fills empty cells) 16.
pub fn points_needed(basis: &MapBasis) -> usize {
    match basis {
        MapBasis::Polynomial { .. } => basis.terms() + 1,
        MapBasis::Spline { .. } => 16,
    }
}

/// Fits a map to a scan: `stage[i]` where the stage put the spot,
/// `measured[i]` where the PSD saw it (mm).
pub fn fit_psd_map(
    stage: &[Vector2<f64>],
    measured: &[Vector2<f64>],
    options: &FitOptions,
) -> Result<PsdMapFit, PsdMapError> {
    let n = measured.len();
    let finite = |p: &Vector2<f64>| p.x.is_finite() && p.y.is_finite();
    if stage.len() != n || !stage.iter().chain(measured).all(finite) {
        return Err(PsdMapError::Unusable {
            reason: "positions and points must be finite and as many".into(),
        });
    }
    let hull = ConvexHull::of_points(measured).map_err(|e| PsdMapError::Unusable {
        reason: format!("the measured points span no area ({e})"),
    })?;
    let (lo, hi) = hull.bounds();
    let frame = MapFrame { min: lo, max: hi };
    let make = |basis: MapBasis| {
        PsdMap::new(basis, frame, Some(hull.clone())).map_err(|e| PsdMapError::Unusable {
            reason: e.to_string(),
        })
    };
    let folds = options.folds.max(2);
    let displacement: Vec<Vector2<f64>> = stage.iter().zip(measured).map(|(s, m)| s - m).collect();
    let train = |basis: &MapBasis| n * (folds - 1) / folds >= points_needed(basis);
    let candidates: Vec<MapBasis> = match options.model {
        ModelChoice::Fixed(basis) => {
            if !train(&basis) {
                return Err(PsdMapError::TooFewPoints {
                    points: n,
                    model: basis.label(),
                    coefficients: basis.terms(),
                    needed: (points_needed(&basis) * folds).div_ceil(folds - 1),
                });
            }
            vec![basis]
        }
        ModelChoice::Auto => {
            let polys = AUTO_POLY_ORDERS.map(|order| MapBasis::Polynomial { order });
            let splines = AUTO_SPLINE_CELLS.iter().map(|&c| MapBasis::Spline {
                cells_x: c,
                cells_y: c,
            });
            // In `auto`, a candidate needs twice its coefficients per fold.
            let list: Vec<MapBasis> = polys
                .chain(splines)
                .filter(|b| train(b) && n * (folds - 1) / folds >= 2 * b.terms())
                .collect();
            if list.is_empty() {
                return Err(PsdMapError::NoCandidate {
                    points: n,
                    needed: (2 * 3 * folds).div_ceil(folds - 1),
                });
            }
            list
        }
    };
    // Robust reference and rejection.
    let reference = match options.model {
        ModelChoice::Fixed(basis) => basis,
        ModelChoice::Auto => {
            let cells = AUTO_SPLINE_CELLS
                .iter()
                .copied()
                .filter(|c| (c + 3) * (c + 3) * 4 <= n)
                .max();
            match cells {
                Some(c) => MapBasis::Spline {
                    cells_x: c,
                    cells_y: c,
                },
                None => *candidates.last().unwrap_or(&candidates[0]),
            }
        }
    };
    let kept = reject_outliers(&make(reference)?, measured, &displacement)?;
    let keep_m: Vec<Vector2<f64>> = kept.iter().map(|&i| measured[i]).collect();
    let keep_d: Vec<Vector2<f64>> = kept.iter().map(|&i| displacement[i]).collect();
    let fold = fold_of_points(keep_m.len(), folds, options.seed);
    let mut scores: Vec<CandidateScore> = Vec::new();
    for basis in &candidates {
        if keep_m.len() * (folds - 1) / folds < points_needed(basis) {
            continue;
        }
        match cross_validate(&make(*basis)?, &keep_m, &keep_d, &fold, folds) {
            Ok(s) => scores.push(s),
            Err(e) if options.model != ModelChoice::Auto => return Err(e),
            Err(_) => {}
        }
    }
    if scores.is_empty() {
        return Err(PsdMapError::TooFewPoints {
            points: keep_m.len(),
            model: reference.label(),
            coefficients: reference.terms(),
            needed: points_needed(&reference),
        });
    }
    let chosen = choose(&scores);
    let map = make(scores[chosen].basis)?;
    let ones = vec![1.0; keep_m.len()];
    let eq = accumulate(&map, &keep_m, &keep_d, &ones);
    let solution = solve(&eq, &penalty(&map.basis()), &map.basis().label())?;
    let block = solution.block();
    let hat = &solution.inverse * &eq.ata;
    let effective_terms = hat.trace();
    let unit_covariance = &hat * &solution.inverse;
    let kept_residuals = residuals(&map, &block, &keep_m, &keep_d);
    let dof = (keep_m.len() as f64 - effective_terms).max(1.0);
    let sigma_mm = Vector2::new(
        (kept_residuals.iter().map(|r| r.x * r.x).sum::<f64>() / dof).sqrt(),
        (kept_residuals.iter().map(|r| r.y * r.y).sum::<f64>() / dof).sqrt(),
    );
    let rms_mm =
        (kept_residuals.iter().map(|r| r.norm_squared()).sum::<f64>() / keep_m.len() as f64).sqrt();
    let mut leverage = 0.0;
    for m in &keep_m {
        let mut phi = DVector::zeros(map.terms());
        map.for_each_term(m, |k, v, _, _| phi[k] = v);
        leverage += (phi.transpose() * &unit_covariance * &phi)[(0, 0)];
    }
    let map_sigma_mm = (leverage / keep_m.len() as f64 * sigma_mm.norm_squared()).sqrt();
    let rejected = (0..n).filter(|i| kept.binary_search(i).is_err()).collect();
    Ok(PsdMapFit {
        residuals: residuals(&map, &block, measured, &displacement),
        cv_rms_mm: scores[chosen].cv_rms_mm,
        candidates: scores
            .iter()
            .map(|s| CandidateResult {
                basis: s.basis,
                cv_rms_mm: s.cv_rms_mm,
            })
            .collect(),
        map,
        block,
        unit_covariance,
        sigma_mm,
        rms_mm,
        map_sigma_mm,
        effective_terms,
        rejected,
    })
}

/// The indices (ascending) of the points a robust fit of `map` keeps.
fn reject_outliers(
    map: &PsdMap,
    measured: &[Vector2<f64>],
    displacement: &[Vector2<f64>],
) -> Result<Vec<usize>, PsdMapError> {
    let p = penalty(&map.basis());
    let label = map.basis().label();
    let mut weights = vec![1.0; measured.len()];
    let mut sigma = 0.0;
    let mut r = Vec::new();
    for _ in 0..MAX_PASSES {
        let eq = accumulate(map, measured, displacement, &weights);
        let block = solve(&eq, &p, &label)?.block();
        r = residuals(map, &block, measured, displacement);
        sigma = robust_sigma(&r, &vec![1.0; r.len()]);
        let next = huber_weights(&r, sigma);
        let change = next
            .iter()
            .zip(&weights)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        weights = next;
        if change < 1e-6 {
            break;
        }
    }
    Ok((0..measured.len())
        .filter(|&i| sigma == 0.0 || r[i].norm() <= REJECT_SIGMAS * sigma)
        .collect())
}
