//! The lens's radial and tangential distortion about the optical centre
//! (docs/model.md §2.2–2.4, the paper's (P7)–(P13)). For the PSD-corrected point
//! `u`:
//!
//! ```text
//! d = u − c,  r² = |d|²,  ρ = k1 r² + k2 r⁴ + k3 r⁶
//! t = (p1 (r² + 2dx²) + 2 p2 dx dy,  p2 (r² + 2dy²) + 2 p1 dx dy)
//! x = u + d ρ + t                                  (the ideal point)
//! ```
//!
//! Writing `x = c + g(d)` with `D = ∂g/∂d`: `∂x/∂u = D`, `∂x/∂c = I − D`,
//! `∂x/∂k_n = d r^{2n}`, `∂x/∂p1 = (r² + 2dx², 2dx dy)`,
//! `∂x/∂p2 = (2dx dy, r² + 2dy²)`.
//!
//! Parameters `cx, cy` (mm; shared with the pinhole), `k1` (mm⁻²), `k2`
//! (mm⁻⁴), `k3` (mm⁻⁶), `p1, p2` (mm⁻¹).

use nalgebra::{Matrix2, Vector2};

use crate::stage::{set_column, ParameterInfo, Stage, StageJacobian};

/// Coefficients of the lens stage, in block order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensCoefficients {
    /// Optical centre, mm.
    pub c: Vector2<f64>,
    /// Radial `k1, k2, k3`.
    pub k: [f64; 3],
    /// Tangential `p1, p2`.
    pub p: [f64; 2],
}

/// Lens radial + tangential distortion centred on the optical centre.
#[derive(Debug, Clone)]
pub struct Lens {
    parameters: Vec<ParameterInfo>,
}

impl Lens {
    /// The stage (parameters `cx, cy, k1, k2, k3, p1, p2`).
    pub fn new() -> Self {
        Self {
            parameters: vec![
                ParameterInfo::new("cx", "mm", 0.0, 1.0),
                ParameterInfo::new("cy", "mm", 0.0, 1.0),
                ParameterInfo::new("k1", "mm^-2", 0.0, 1e-3),
                ParameterInfo::new("k2", "mm^-4", 0.0, 1e-5),
                ParameterInfo::new("k3", "mm^-6", 0.0, 1e-7),
                ParameterInfo::new("p1", "mm^-1", 0.0, 1e-4),
                ParameterInfo::new("p2", "mm^-1", 0.0, 1e-4),
            ],
        }
    }

    /// The map with its optional Jacobians (`wrt_params` in block order).
    #[inline]
    pub fn eval(
        lens: &LensCoefficients,
        u: &Vector2<f64>,
        jacobian: Option<(&mut Matrix2<f64>, &mut [f64])>,
    ) -> Vector2<f64> {
        let ([k1, k2, k3], [p1, p2]) = (lens.k, lens.p);
        let dx = u.x - lens.c.x;
        let dy = u.y - lens.c.y;
        let r2 = dx * dx + dy * dy;
        let rho = r2 * (k1 + r2 * (k2 + r2 * k3));
        let tx = p1 * (r2 + 2.0 * dx * dx) + 2.0 * p2 * dx * dy;
        let ty = p2 * (r2 + 2.0 * dy * dy) + 2.0 * p1 * dx * dy;
        if let Some((wrt_input, wrt_params)) = jacobian {
            let rho_prime = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
            let dmat = Matrix2::new(
                1.0 + rho + 2.0 * dx * dx * rho_prime + 6.0 * p1 * dx + 2.0 * p2 * dy,
                2.0 * dx * dy * rho_prime + 2.0 * p1 * dy + 2.0 * p2 * dx,
                2.0 * dx * dy * rho_prime + 2.0 * p2 * dx + 2.0 * p1 * dy,
                1.0 + rho + 2.0 * dy * dy * rho_prime + 6.0 * p2 * dy + 2.0 * p1 * dx,
            );
            *wrt_input = dmat;
            let dc = Matrix2::identity() - dmat;
            set_column(wrt_params, 0, dc.column(0).into_owned());
            set_column(wrt_params, 1, dc.column(1).into_owned());
            let d = Vector2::new(dx, dy);
            set_column(wrt_params, 2, d * r2);
            set_column(wrt_params, 3, d * (r2 * r2));
            set_column(wrt_params, 4, d * (r2 * r2 * r2));
            set_column(
                wrt_params,
                5,
                Vector2::new(r2 + 2.0 * dx * dx, 2.0 * dx * dy),
            );
            set_column(
                wrt_params,
                6,
                Vector2::new(2.0 * dx * dy, r2 + 2.0 * dy * dy),
            );
        }
        Vector2::new(u.x + dx * rho + tx, u.y + dy * rho + ty)
    }
}

impl Default for Lens {
    fn default() -> Self {
        Self::new()
    }
}

impl Stage for Lens {
    fn kind(&self) -> &str {
        "lens"
    }

    fn parameters(&self) -> &[ParameterInfo] {
        &self.parameters
    }

    fn apply(
        &self,
        params: &[f64],
        input: &Vector2<f64>,
        jacobian: Option<StageJacobian<'_>>,
    ) -> Vector2<f64> {
        let lens = LensCoefficients {
            c: Vector2::new(params[0], params[1]),
            k: [params[2], params[3], params[4]],
            p: [params[5], params[6]],
        };
        Self::eval(&lens, input, jacobian.map(|j| (j.wrt_input, j.wrt_params)))
    }

    fn example_parameters(&self) -> Vec<Vec<f64>> {
        vec![
            vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            vec![0.5, -0.7, 2e-3, 0.0, 0.0, 0.0, 0.0],
            vec![0.5, -0.7, 1e-2, 3e-5, 0.0, 0.0, 0.0],
            vec![-0.3, 0.4, 5e-3, -2e-5, 1e-7, 2e-4, -3e-4],
        ]
    }

    fn clone_box(&self) -> Box<dyn Stage> {
        Box::new(self.clone())
    }
}
