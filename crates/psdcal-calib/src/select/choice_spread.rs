//! The uncertainty of the choice itself (docs/model.md §4.8): the chosen
//! parameters' covariance widened by the neighbouring models the data could
//! as well have chosen.
//!
//! A neighbour is the chosen model without one of the groups the choice
//! took. Its estimate differs from the chosen one by `δ_k` (over the chosen
//! parameters; a parameter the neighbour does not free counts at the value
//! it is held at, zero). Another data set from the same sensor would not
//! take the group with about the probability
//!
//! ```text
//! p_k = 1 − P(T > 1) · P(LM > c_k),    P(T > 1) = Φ(t − 1),
//! P(LM > c_k) = Φ(√LM − √c_k)
//! ```
//!
//! with `t` the held-out test's statistic in standard errors (the larger of
//! the differences' and the log ratios'), `c_k` the evidence threshold and
//! `√LM` the score statistic's normal approximation. The covariance becomes
//!
//! ```text
//! C = C_θ + Σ_k p_k δ_k δ_kᵀ
//! ```
//!
//! the first-order variance of the mixture over the models (positive
//! semi-definite by construction). Where the model is exact the groups are
//! screened out or rejected with small `p_k` and `δ_k`, and `C = C_θ`.

use nalgebra::{DMatrix, DVector};

use crate::select::candidate::Scored;

/// A neighbouring model: its estimate's difference from the chosen one and
/// the probability that the data would choose it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Neighbour {
    /// The group's freed parameters (for the report).
    pub free: Vec<String>,
    /// `(parameter, chosen − neighbour)` for each chosen parameter.
    pub delta: Vec<(String, f64)>,
    /// `p_k`.
    pub probability: f64,
}

/// The least probability of a neighbour that counts. The normal
/// approximations are not accurate in their far tails, and a neighbour the
/// data reject that strongly is no alternative: without the aspect on 2:1
/// pixels (`p` about 1e-5), its `δ_f` of millimetres doubled σ(f).
pub const PLAUSIBLE: f64 = 0.01;

/// The standard normal distribution function (Abramowitz–Stegun 7.1.26 on
/// erfc; absolute error below 1.5e-7).
pub(crate) fn normal_cdf(z: f64) -> f64 {
    let x = z.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let erfc = poly * (-x * x).exp();
    if z >= 0.0 {
        1.0 - 0.5 * erfc
    } else {
        0.5 * erfc
    }
}

/// The probability that another data set passes the group:
/// `Φ(t − pass) · Φ(√LM − √c)` (no score statistic: the held-out part
/// only).
pub(crate) fn pass_probability(t: f64, pass: f64, lm: Option<f64>, threshold: f64) -> f64 {
    let held_out = normal_cdf(t - pass);
    let evidence = lm.map_or(1.0, |lm| normal_cdf(lm.max(0.0).sqrt() - threshold.sqrt()));
    held_out * evidence
}

/// `(name, a − b)` over the parameters either fit frees (`names`).
pub(crate) fn difference_of(a: &Scored, b: &Scored, names: &[String]) -> Vec<(String, f64)> {
    names
        .iter()
        .map(|n| {
            let value = |s: &Scored| s.refined.model.get(n).unwrap_or(0.0);
            (n.clone(), value(a) - value(b))
        })
        .collect()
}

/// `Σ_k p_k δ_k δ_kᵀ` over `names` (the chosen parameters, covariance
/// order).
pub(crate) fn choice_covariance(neighbours: &[Neighbour], names: &[String]) -> DMatrix<f64> {
    let p = names.len();
    let mut c = DMatrix::zeros(p, p);
    for n in neighbours.iter().filter(|n| n.probability >= PLAUSIBLE) {
        let d = DVector::from_iterator(
            p,
            names.iter().map(|name| {
                n.delta
                    .iter()
                    .find(|(m, _)| m == name)
                    .map_or(0.0, |(_, v)| *v)
            }),
        );
        c += n.probability * &d * d.transpose();
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_cdf_matches_its_table() {
        // Φ(0) = 1/2, Φ(1) = 0.841345, Φ(−1.96) = 0.024998, Φ(3) = 0.998650.
        for (z, p) in [
            (0.0, 0.5),
            (1.0, 0.841_345),
            (-1.96, 0.024_998),
            (3.0, 0.998_650),
        ] {
            assert!(
                (normal_cdf(z) - p).abs() < 2e-6,
                "Φ({z}) = {}",
                normal_cdf(z)
            );
        }
    }

    #[test]
    fn the_spread_is_the_weighted_outer_products() {
        let names = vec!["f".to_string(), "cx".to_string()];
        let neighbours = [
            Neighbour {
                free: vec!["skew".into()],
                delta: vec![("f".into(), 2.0), ("cx".into(), -1.0)],
                probability: 0.25,
            },
            Neighbour {
                free: vec!["k3".into()],
                delta: vec![("f".into(), 1.0)],
                probability: 0.5,
            },
            Neighbour {
                free: vec!["a".into()],
                delta: vec![("f".into(), 1e3)],
                probability: 1e-5,
            },
        ];
        let c = choice_covariance(&neighbours, &names);
        // 0.25 (4, −2; −2, 1) + 0.5 (1, 0; 0, 0); the implausible third
        // not counted.
        assert_eq!(c, DMatrix::from_row_slice(2, 2, &[1.5, -0.5, -0.5, 0.25]));
    }
}
