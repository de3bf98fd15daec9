//! Line-straightness cost of the preliminary distortion correction
//! (docs/model.md §4.1; the paper's Section 3.2, (P30)–(P35), here in the
//! Devernay–Faugeras total-least-squares form).
//!
//! For every declared template line seen with at least 3 of its LEDs in an
//! image, with corrected points `p_j` (see [`crate::preliminary`] for the
//! correction `p = c + d(1 + u1 ρ + u2 ρ²)`, `d = m − c`, `ρ = ‖d‖²/R²`):
//!
//! ```text
//! p̄ = mean p_j,   v_j = p_j − p̄,   C = Σ v_j v_jᵀ = λ_max u uᵀ + λ_min n nᵀ
//! e_j = n·v_j / √λ_max,     Σ_j e_j² = λ_min / λ_max
//! ```
//!
//! i.e. the orthogonal distances to the total-least-squares line, divided by
//! the root of the scatter along it: scale-free, so shrinking the points does
//! not reduce the cost. The Jacobian is analytic: with `∂p_j/∂u1 = d_j ρ_j`,
//! `∂p_j/∂u2 = d_j ρ_j²` and `δv_j = δp_j − mean δp`,
//!
//! ```text
//! δe_j = n·δv_j / √λ_max − e_j δλ_max / (2 λ_max),   δλ_max = 2 Σ_j (u·v_j)(u·δv_j)
//! ```
//!
//! plus the rotation of the normal, `δn = (uᵀ δC n)/(λ_min − λ_max) u` with
//! `uᵀ δC n = Σ_j (u·δv_j)(n·v_j) + (u·v_j)(n·δv_j)`, contributing
//! `δn·v_j / √λ_max` (the rotation of `u` does not change `λ_max` to first
//! order). The Jacobian is therefore exact, and Gauss–Newton converges
//! quadratically near a small-residual minimum. A line whose two principal
//! spreads coincide has no defined direction and contributes zeros.

use nalgebra::{DMatrix, DVector, Vector2};

use crate::start::correction_cost::TwoParameterCost;
use crate::{CalibError, CalibrationData};

/// One line seen in one image: its measured points.
struct Term {
    measured: Vec<Vector2<f64>>,
}

/// Lines of at least 3 observed LEDs, over all images.
pub fn usable_lines(data: &CalibrationData) -> usize {
    line_terms(data).len()
}

fn line_terms(data: &CalibrationData) -> Vec<Term> {
    let mut terms = Vec::new();
    for im in &data.images {
        for line in &data.lines {
            let measured: Vec<_> = line
                .iter()
                .filter_map(|&led| im.points.iter().find(|o| o.led == led).map(|o| o.measured))
                .collect();
            if measured.len() >= 3 {
                terms.push(Term { measured });
            }
        }
    }
    terms
}

/// The line-straightness cost over every usable (line, image) pair.
pub(crate) struct StraightnessCost {
    terms: Vec<Term>,
    centre: Vector2<f64>,
    radius: f64,
}

impl StraightnessCost {
    /// The cost of `data`'s lines for a correction centred on `centre`, with
    /// radius scale `radius` (mm).
    pub(crate) fn new(
        data: &CalibrationData,
        centre: Vector2<f64>,
        radius: f64,
    ) -> Result<Self, CalibError> {
        let terms = line_terms(data);
        if terms.is_empty() {
            return Err(CalibError::InvalidInput {
                reason: "line-straightness correction needs template lines with at least 3 LEDs \
                         observed in an image; the template declares none (use the \
                         homography-consistency correction)"
                    .into(),
            });
        }
        Ok(Self {
            terms,
            centre,
            radius,
        })
    }

    /// Number of (line, image) terms.
    pub(crate) fn lines(&self) -> usize {
        self.terms.len()
    }

    /// Residuals and, when asked, their Jacobian.
    fn evaluate(&self, u: [f64; 2], jacobian: bool) -> (DVector<f64>, Option<DMatrix<f64>>) {
        let n: usize = self.terms.iter().map(|t| t.measured.len()).sum();
        let mut r = DVector::zeros(n);
        let mut j = jacobian.then(|| DMatrix::zeros(n, 2));
        let mut row = 0;
        for term in &self.terms {
            let m = term.measured.len();
            let mut p = Vec::with_capacity(m);
            let mut dp = Vec::with_capacity(m);
            for x in &term.measured {
                let d = x - self.centre;
                let rho = d.norm_squared() / (self.radius * self.radius);
                p.push(self.centre + d * (1.0 + rho * (u[0] + rho * u[1])));
                dp.push([d * rho, d * (rho * rho)]);
            }
            let mean = p.iter().fold(Vector2::zeros(), |a, q| a + q) / m as f64;
            let v: Vec<_> = p.iter().map(|q| q - mean).collect();
            let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
            for w in &v {
                a += w.x * w.x;
                b += w.x * w.y;
                c += w.y * w.y;
            }
            let theta = 0.5 * (2.0 * b).atan2(a - c);
            let dir = Vector2::new(theta.cos(), theta.sin());
            let normal = Vector2::new(-theta.sin(), theta.cos());
            let lmax: f64 = v.iter().map(|w| dir.dot(w).powi(2)).sum();
            let lmin: f64 = v.iter().map(|w| normal.dot(w).powi(2)).sum();
            if lmax.is_nan() || lmax <= 0.0 || lmax - lmin <= 1e-12 * lmax {
                // All points of the line coincide: no information (zeros).
                row += m;
                continue;
            }
            let sl = lmax.sqrt();
            for (k, w) in v.iter().enumerate() {
                r[row + k] = normal.dot(w) / sl;
            }
            if let Some(j) = j.as_mut() {
                for col in 0..2 {
                    let dmean = dp.iter().fold(Vector2::zeros(), |acc, d| acc + d[col]) / m as f64;
                    let dv: Vec<_> = dp.iter().map(|d| d[col] - dmean).collect();
                    let dl: f64 = 2.0
                        * v.iter()
                            .zip(&dv)
                            .map(|(w, dw)| dir.dot(w) * dir.dot(dw))
                            .sum::<f64>();
                    // Rotation of the normal: δn = (uᵀ δC n)/(λ_min − λ_max) u.
                    let u_dc_n: f64 = v
                        .iter()
                        .zip(&dv)
                        .map(|(w, dw)| dir.dot(dw) * normal.dot(w) + dir.dot(w) * normal.dot(dw))
                        .sum();
                    let dn = dir * (u_dc_n / (lmin - lmax));
                    for k in 0..m {
                        j[(row + k, col)] = (normal.dot(&dv[k]) + dn.dot(&v[k])) / sl
                            - r[row + k] * dl / (2.0 * lmax);
                    }
                }
            }
            row += m;
        }
        (r, j)
    }
}

impl TwoParameterCost for StraightnessCost {
    fn residuals(&self, u: [f64; 2]) -> Result<DVector<f64>, CalibError> {
        let (r, _) = self.evaluate(u, false);
        if r.iter().all(|v| v.is_finite()) {
            Ok(r)
        } else {
            Err(CalibError::Numerical {
                stage: "line straightness",
                reason: "non-finite residual".into(),
            })
        }
    }

    fn jacobian(&self, u: [f64; 2], _r: &DVector<f64>) -> Result<DMatrix<f64>, CalibError> {
        match self.evaluate(u, true) {
            (_, Some(j)) if j.iter().all(|v| v.is_finite()) => Ok(j),
            _ => Err(CalibError::Numerical {
                stage: "line straightness",
                reason: "non-finite Jacobian".into(),
            }),
        }
    }

    fn jacobian_evaluations(&self) -> usize {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ImageObservations, Observation};
    use psdcal_model::PsdGeometry;

    /// The analytic Jacobian equals central finite differences of the residuals.
    #[test]
    fn analytic_jacobian_matches_finite_differences() {
        let template: Vec<_> = (0..5)
            .flat_map(|i| (0..5).map(move |j| Vector2::new(i as f64, j as f64)))
            .collect();
        let lines: Vec<Vec<usize>> = (0..5)
            .map(|i| (0..5).map(|j| 5 * i + j).collect())
            .collect();
        let points = template
            .iter()
            .enumerate()
            .map(|(led, p)| {
                let q = Vector2::new(p.x - 2.2, p.y * 0.9 - 1.7 + 0.1 * p.x);
                let r2 = q.norm_squared();
                Observation {
                    led,
                    measured: q * (1.0 - 0.02 * r2),
                }
            })
            .collect();
        let data = CalibrationData {
            amplitudes: None,
            noise_scale: None,
            template,
            lines,
            images: vec![ImageObservations {
                id: "a".into(),
                points,
            }],
            geometry: PsdGeometry::default(),
        };
        let cost = StraightnessCost::new(&data, Vector2::new(0.1, -0.2), 3.0).unwrap();
        let u = [0.05, -0.01];
        let r = cost.residuals(u).unwrap();
        let j = cost.jacobian(u, &r).unwrap();
        for k in 0..2 {
            let h = 1e-6;
            let (mut up, mut um) = (u, u);
            up[k] += h;
            um[k] -= h;
            let fd = (cost.residuals(up).unwrap() - cost.residuals(um).unwrap()) / (2.0 * h);
            let err = (j.column(k) - &fd).norm();
            assert!(
                err <= 1e-7 * fd.norm(),
                "column {k}: {} vs {} (error {err:.3e})",
                j.column(k),
                fd
            );
        }
    }
}
