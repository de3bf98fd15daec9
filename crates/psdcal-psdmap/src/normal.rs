//! The normal equations of a map's coefficients (docs/model.md §8.3).
//!
//! A scan gives pairs (measured `m_i`, stage position `s_i`); the map's
//! displacement `d_i = s_i − m_i` is linear in the coefficients, one axis at
//! a time with the same design: `d_x = A a_x`, `d_y = A a_y`,
//! `A_ik = φ_k(m_i)`. With weights `w_i` (0 drops a point) and a penalty `P`
//! (scaled by `λ`), each axis solves
//!
//! ```text
//! (AᵀWA + λP) a = AᵀW d
//! ```
//!
//! [`NormalEquations`] accumulates `AᵀWA` and the right-hand sides row by
//! row, visiting only a spline's 16 non-zero basis functions.

use nalgebra::{DMatrix, DVector, Vector2};
use psdcal_model::stages::psd_map::MAX_POLY_ORDER;
use psdcal_model::stages::PsdMap;

/// The most basis functions non-zero at a point: a polynomial of the
/// highest order (a spline has 16).
const MAX_TERMS: usize = (MAX_POLY_ORDER + 1) * (MAX_POLY_ORDER + 2) / 2;

/// `AᵀWA`, `AᵀW d_x`, `AᵀW d_y` and the weight sum.
#[derive(Debug, Clone)]
pub struct NormalEquations {
    /// `AᵀWA` (K×K, symmetric).
    pub ata: DMatrix<f64>,
    /// `AᵀW d_x`.
    pub atx: DVector<f64>,
    /// `AᵀW d_y`.
    pub aty: DVector<f64>,
    /// `Σ w_i`.
    pub weight: f64,
}

impl NormalEquations {
    /// Empty equations for `k` coefficients per axis.
    pub fn zeros(k: usize) -> Self {
        Self {
            ata: DMatrix::zeros(k, k),
            atx: DVector::zeros(k),
            aty: DVector::zeros(k),
            weight: 0.0,
        }
    }

    /// Adds point `m` with displacement `d` and weight `w`.
    pub fn add(&mut self, map: &PsdMap, m: &Vector2<f64>, d: &Vector2<f64>, w: f64) {
        if w == 0.0 {
            return;
        }
        // At most 91 basis functions are non-zero at a point (order 12).
        let mut idx = [0usize; MAX_TERMS];
        let mut val = [0.0f64; MAX_TERMS];
        let mut n = 0;
        map.for_each_term(m, |k, phi, _, _| {
            if n < MAX_TERMS {
                idx[n] = k;
                val[n] = phi;
                n += 1;
            }
        });
        for r in 0..n {
            let (a, wa) = (idx[r], w * val[r]);
            self.atx[a] += wa * d.x;
            self.aty[a] += wa * d.y;
            for s in 0..n {
                let b = idx[s];
                if b >= a {
                    self.ata[(a, b)] += wa * val[s];
                }
            }
        }
        self.weight += w;
    }

    /// Mirrors the upper triangle into the lower one (call once after
    /// accumulating).
    pub fn symmetrize(&mut self) {
        let k = self.ata.nrows();
        for a in 0..k {
            for b in 0..a {
                self.ata[(a, b)] = self.ata[(b, a)];
            }
        }
    }

    /// The equations of everything in `self` but not in `other` (a fold's
    /// training set from the whole set and the held-out points).
    pub fn minus(&self, other: &Self) -> Self {
        Self {
            ata: &self.ata - &other.ata,
            atx: &self.atx - &other.atx,
            aty: &self.aty - &other.aty,
            weight: self.weight - other.weight,
        }
    }
}

/// The equations of `points` (measured, displacement) with `weights`.
pub fn accumulate(
    map: &PsdMap,
    measured: &[Vector2<f64>],
    displacement: &[Vector2<f64>],
    weights: &[f64],
) -> NormalEquations {
    let mut eq = NormalEquations::zeros(map.terms());
    for ((m, d), w) in measured.iter().zip(displacement).zip(weights) {
        eq.add(map, m, d, *w);
    }
    eq.symmetrize();
    eq
}
