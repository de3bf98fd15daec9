//! The PSD's radial distortion about the electrical centre (docs/model.md §2.1,
//! the paper's (P14)–(P16)):
//!
//! ```text
//! h² = xd² + yd²,   s = 1 + l1 h² + l2 h⁴,   (xu, yu) = s · (xd, yd)
//! ∂u/∂m = s I + 2 s' m mᵀ   with s' = l1 + 2 l2 h²
//! ∂u/∂l1 = m h²,  ∂u/∂l2 = m h⁴
//! ```
//!
//! Parameters `l1` (mm⁻²), `l2` (mm⁻⁴).

use nalgebra::{Matrix2, Vector2};

use crate::stage::{set_column, ParameterInfo, Stage, StageJacobian};

/// PSD radial distortion `(l1, l2)` centred on `(0, 0)`.
#[derive(Debug, Clone)]
pub struct PsdRadial {
    parameters: Vec<ParameterInfo>,
}

impl PsdRadial {
    /// The stage (parameters `l1`, `l2`).
    pub fn new() -> Self {
        Self {
            parameters: vec![
                ParameterInfo::new("l1", "mm^-2", 0.0, 1e-3),
                ParameterInfo::new("l2", "mm^-4", 0.0, 1e-5),
            ],
        }
    }

    /// The map with its optional Jacobians, for callers holding `(l1, l2)`.
    #[inline]
    pub fn eval(
        l1: f64,
        l2: f64,
        m: &Vector2<f64>,
        jacobian: Option<(&mut Matrix2<f64>, &mut [f64])>,
    ) -> Vector2<f64> {
        let h2 = m.x * m.x + m.y * m.y;
        let s = 1.0 + h2 * (l1 + h2 * l2);
        if let Some((wrt_input, wrt_params)) = jacobian {
            let s_prime = l1 + 2.0 * l2 * h2;
            *wrt_input = Matrix2::new(
                s + 2.0 * s_prime * m.x * m.x,
                2.0 * s_prime * m.x * m.y,
                2.0 * s_prime * m.x * m.y,
                s + 2.0 * s_prime * m.y * m.y,
            );
            set_column(wrt_params, 0, m * h2);
            set_column(wrt_params, 1, m * (h2 * h2));
        }
        Vector2::new(m.x * s, m.y * s)
    }
}

impl Default for PsdRadial {
    fn default() -> Self {
        Self::new()
    }
}

impl Stage for PsdRadial {
    fn kind(&self) -> &str {
        "psd_radial"
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
        Self::eval(
            params[0],
            params[1],
            input,
            jacobian.map(|j| (j.wrt_input, j.wrt_params)),
        )
    }

    fn example_parameters(&self) -> Vec<Vec<f64>> {
        vec![
            vec![0.0, 0.0],
            vec![crate::SensorModel::PAPER_L1, 0.0],
            vec![2e-3, -1e-5],
        ]
    }

    fn clone_box(&self) -> Box<dyn Stage> {
        Box::new(self.clone())
    }
}
