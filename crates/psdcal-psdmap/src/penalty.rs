//! The smoothness penalty of a spline map (docs/model.md §8.3): the sum of
//! squared second differences of the control values along both grid
//! directions (a P-spline penalty),
//!
//! ```text
//! aᵀ P a = Σ_ij (a_{i+1,j} − 2 a_ij + a_{i−1,j})² + Σ_ij (a_{i,j+1} − 2 a_ij + a_{i,j−1})²
//! ```
//!
//! Its null space is the planes `a_ij = α + β i + γ j`, which every scan
//! determines; where the scan leaves cells empty, the penalty continues the
//! field with the least curvature. A polynomial map has no penalty.
//!
//! The weight is `λ = κ · tr(AᵀWA) / tr(P)` with `κ` = [`PENALTY_KAPPA`]:
//! scale-free, and small enough that where the scan is dense the data
//! decide (a cubic field, which a cubic spline reproduces exactly, is
//! changed by less than 1e-3 of its second differences).

use nalgebra::DMatrix;
use psdcal_model::stages::MapBasis;

/// The penalty's relative weight `κ`.
pub const PENALTY_KAPPA: f64 = 1e-6;

/// `P` for `basis` (zero for a polynomial), K×K.
pub fn penalty(basis: &MapBasis) -> DMatrix<f64> {
    let k = basis.terms();
    let mut p = DMatrix::zeros(k, k);
    let MapBasis::Spline { cells_x, cells_y } = *basis else {
        return p;
    };
    let (nx, ny) = (cells_x + 3, cells_y + 3);
    let index = |i: usize, j: usize| i * ny + j;
    let mut add = |a: usize, b: usize, c: usize| {
        let t = [(a, 1.0), (b, -2.0), (c, 1.0)];
        for (r, vr) in t {
            for (s, vs) in t {
                p[(r, s)] += vr * vs;
            }
        }
    };
    for j in 0..ny {
        for i in 1..nx - 1 {
            add(index(i - 1, j), index(i, j), index(i + 1, j));
        }
    }
    for i in 0..nx {
        for j in 1..ny - 1 {
            add(index(i, j - 1), index(i, j), index(i, j + 1));
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use nalgebra::DVector;

    use super::*;

    #[test]
    fn planes_cost_nothing_and_curvature_costs() {
        let basis = MapBasis::Spline {
            cells_x: 3,
            cells_y: 2,
        };
        let p = penalty(&basis);
        let ny = 5;
        let plane = DVector::from_iterator(
            30,
            (0..30).map(|k| 1.0 + 0.5 * (k / ny) as f64 - 0.25 * (k % ny) as f64),
        );
        assert!((plane.transpose() * &p * &plane)[(0, 0)].abs() < 1e-12);
        // a_ij = i²: second difference 2 along x at each of 4 interior
        // columns and 5 rows: 20 terms of 4.
        let bowl = DVector::from_iterator(30, (0..30).map(|k| ((k / ny) as f64).powi(2)));
        assert!(((bowl.transpose() * &p * &bowl)[(0, 0)] - 80.0).abs() < 1e-9);
        assert_eq!(penalty(&MapBasis::Polynomial { order: 3 }).norm(), 0.0);
    }
}
