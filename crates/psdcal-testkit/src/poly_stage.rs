//! A test-only stage with a large parameter block: a tensor-product
//! polynomial displacement field `out = in + Σ_ij (cx_ij, cy_ij) u^i v^j`,
//! `u = x/h`, `v = y/h`, `0 ≤ i, j < n` (2n² coefficients; n = 10 gives 200).
//! It shows that a stage with hundreds of coefficients is as easy to add as
//! one with two.

use nalgebra::{Matrix2, Vector2};
use psdcal_model::stage::{set_column, ParameterInfo, Stage, StageJacobian};

/// The polynomial displacement stage.
#[derive(Debug, Clone)]
pub struct PolyField {
    n: usize,
    half: f64,
    parameters: Vec<ParameterInfo>,
}

impl PolyField {
    /// `n × n` monomials per axis over a sensor of half-side `half` mm.
    pub fn new(n: usize, half: f64) -> Self {
        let mut parameters = Vec::new();
        for axis in ["x", "y"] {
            for i in 0..n {
                for j in 0..n {
                    parameters.push(ParameterInfo::new(
                        format!("poly_{axis}_{i}_{j}"),
                        "mm",
                        0.0,
                        1e-3,
                    ));
                }
            }
        }
        Self {
            n,
            half,
            parameters,
        }
    }

    fn powers(&self, t: f64) -> (Vec<f64>, Vec<f64>) {
        let mut p = vec![1.0; self.n];
        let mut d = vec![0.0; self.n];
        for k in 1..self.n {
            p[k] = p[k - 1] * t;
            d[k] = k as f64 * p[k - 1];
        }
        (p, d)
    }
}

impl Stage for PolyField {
    fn kind(&self) -> &str {
        "test_poly_field"
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
        let (u, v) = (input.x / self.half, input.y / self.half);
        let (pu, du) = self.powers(u);
        let (pv, dv) = self.powers(v);
        let nn = self.n * self.n;
        let mut out = *input;
        let mut d = Matrix2::identity();
        let mut jac = jacobian;
        for i in 0..self.n {
            for j in 0..self.n {
                let k = i * self.n + j;
                let basis = pu[i] * pv[j];
                let (ax, ay) = (params[k], params[nn + k]);
                out.x += ax * basis;
                out.y += ay * basis;
                let (bu, bv) = (du[i] * pv[j] / self.half, pu[i] * dv[j] / self.half);
                d[(0, 0)] += ax * bu;
                d[(0, 1)] += ax * bv;
                d[(1, 0)] += ay * bu;
                d[(1, 1)] += ay * bv;
                if let Some(j) = jac.as_mut() {
                    set_column(j.wrt_params, k, Vector2::new(basis, 0.0));
                    set_column(j.wrt_params, nn + k, Vector2::new(0.0, basis));
                }
            }
        }
        if let Some(j) = jac {
            *j.wrt_input = d;
        }
        out
    }

    fn example_parameters(&self) -> Vec<Vec<f64>> {
        let len = self.parameters.len();
        // Smooth fields of a few µm to tens of µm, decaying with the order.
        let field = |seed: f64| -> Vec<f64> {
            (0..len)
                .map(|k| {
                    let (i, j) = ((k % (self.n * self.n)) / self.n, k % self.n);
                    let order = (i + j) as f64;
                    1e-2 * (seed * (k as f64 + 1.0)).sin() / (1.0 + order).powi(3)
                })
                .collect()
        };
        vec![vec![0.0; len], field(0.7), field(1.9)]
    }

    fn clone_box(&self) -> Box<dyn Stage> {
        Box::new(self.clone())
    }
}
