//! Robustness to a few bad scan points (docs/model.md §8.3).
//!
//! Scale: for 2-D Gaussian residuals of σ per axis the norm `|r|` is
//! Rayleigh distributed with median `σ √(2 ln 2) ≈ 1.1774 σ`, so
//! `σ̂ = median|r| / 1.1774`.
//!
//! A reference fit is iteratively reweighted with Huber weights on the norm,
//! `w = 1` for `|r| ≤ c σ̂`, `c σ̂ / |r|` beyond (`c` = [`HUBER_C`]), until the
//! weights settle; then points with `|r| > k σ̂` (`k` = [`REJECT_SIGMAS`];
//! a Gaussian point exceeds 5σ̂ with probability `e^{−12.5} ≈ 4e-6`) are
//! rejected, and the map is fitted to the others by plain least squares.

use nalgebra::Vector2;

/// Huber's threshold, in σ̂.
pub const HUBER_C: f64 = 2.5;
/// Rejection threshold, in σ̂.
pub const REJECT_SIGMAS: f64 = 5.0;
/// `median |r| / σ` of a 2-D Gaussian.
pub const RAYLEIGH_MEDIAN: f64 = 1.177_410_022_515_474_6;
/// Reweighting passes at most.
pub const MAX_PASSES: usize = 20;

/// `σ̂` of the residuals with positive weight (0 when there are none).
pub fn robust_sigma(residuals: &[Vector2<f64>], weights: &[f64]) -> f64 {
    let mut norms: Vec<f64> = residuals
        .iter()
        .zip(weights)
        .filter(|(_, w)| **w > 0.0)
        .map(|(r, _)| r.norm())
        .collect();
    if norms.is_empty() {
        return 0.0;
    }
    norms.sort_by(f64::total_cmp);
    let n = norms.len();
    let median = if n % 2 == 1 {
        norms[n / 2]
    } else {
        0.5 * (norms[n / 2 - 1] + norms[n / 2])
    };
    median / RAYLEIGH_MEDIAN
}

/// Huber weights of the residuals at scale `sigma` (all 1 when `sigma` is 0).
pub fn huber_weights(residuals: &[Vector2<f64>], sigma: f64) -> Vec<f64> {
    residuals
        .iter()
        .map(|r| {
            let n = r.norm();
            let t = HUBER_C * sigma;
            if sigma > 0.0 && n > t {
                t / n
            } else {
                1.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    use super::*;

    #[test]
    fn the_scale_of_gaussian_residuals_is_their_sigma() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let normal = Normal::new(0.0, 2e-3).unwrap();
        let r: Vec<_> = (0..20000)
            .map(|_| Vector2::new(normal.sample(&mut rng), normal.sample(&mut rng)))
            .collect();
        let s = robust_sigma(&r, &vec![1.0; r.len()]);
        // The median of 20 000 Rayleigh draws: relative sd ≈ 0.8 %.
        assert!((s / 2e-3 - 1.0).abs() < 0.03, "{s}");
        let w = huber_weights(&[Vector2::new(1.0, 0.0), Vector2::new(0.0, 1e-3)], 1e-2);
        assert_eq!(w, [0.025, 1.0]);
    }
}
