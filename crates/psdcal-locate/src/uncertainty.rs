//! Uncertainty of a ray from the calibration's covariance and from the
//! measurement noise (first-order propagation, docs/model.md §5 with §4.6).
//!
//! With `θ̂` the estimated quantities (a subset of the model parameters of
//! `Param::ALL` and, when an electrical calibration estimated them, the
//! relative gains `g_x2, g_y1, g_y2`) and `Σ_θ` their covariance:
//!
//! ```text
//! Σ_ab,cal  = J_θ Σ_θ J_θᵀ           J_θ = ∂(a, b)/∂θ̂  (gain columns: ∂(a,b)/∂m · ∂m/∂g)
//! Σ_ab,meas = σ_m² J_m J_mᵀ          J_m = ∂(a, b)/∂m, σ_m the point noise per coordinate, mm
//! Σ_α       = D (Σ_ab,cal + Σ_ab,meas) D,   D = ∂α/∂(a, b) = diag(1/(1+a²), 1/(1+b²))
//! ```
//!
//! This is the linearisation of the uncertainty behind the paper's
//! sensitivity analysis (P40)–(P42): instead of worst-case bounds per
//! parameter, the full covariance with its correlations. `(a, b)` are
//! dimensionless, angles in radians; `Σ` in their units squared.

use nalgebra::{DMatrix, Matrix2, Matrix2x3, SMatrix};
use psdcal_model::{Param, N_PARAMS};

use crate::error::LocateError;

/// Names of the relative channel gains in a calibration's covariance.
pub const GAIN_NAMES: [&str; 3] = ["g_x2", "g_y1", "g_y2"];

/// One estimated quantity: a model parameter, or a relative channel gain
/// (`0` = g_x2, `1` = g_y1, `2` = g_y2, the column order of
/// `psdcal_model::sensor::impact_point_gain_jacobian`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Estimated {
    /// A sensor model parameter.
    Model(Param),
    /// A relative channel gain, by index in `(g_x2, g_y1, g_y2)`.
    Gain(usize),
}

impl Estimated {
    /// The name used in calibration.json.
    pub fn name(&self) -> &'static str {
        match self {
            Estimated::Model(p) => p.name(),
            Estimated::Gain(k) => GAIN_NAMES.get(*k).copied().unwrap_or("g_?"),
        }
    }

    /// Parses a name of calibration.json (`f`, `cx`, …, `g_x2`, …).
    pub fn parse(name: &str) -> Result<Self, LocateError> {
        if let Some(k) = GAIN_NAMES.iter().position(|g| *g == name.trim()) {
            return Ok(Estimated::Gain(k));
        }
        name.parse::<Param>()
            .map(Estimated::Model)
            .map_err(|e| LocateError::InvalidCovariance {
                reason: format!("{e}, or g_x2, g_y1, g_y2"),
            })
    }
}

/// The covariance of a calibration's estimated quantities.
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterCovariance {
    entries: Vec<Estimated>,
    matrix: DMatrix<f64>,
}

impl Default for ParameterCovariance {
    fn default() -> Self {
        Self::none()
    }
}

impl ParameterCovariance {
    /// No uncertainty (nothing estimated).
    pub fn none() -> Self {
        Self {
            entries: Vec::new(),
            matrix: DMatrix::zeros(0, 0),
        }
    }

    /// A covariance of `entries`; the matrix must be square, finite,
    /// symmetric (relative 1e-9) with non-negative diagonal, and no entry may
    /// appear twice. It is stored symmetrised.
    pub fn new(entries: Vec<Estimated>, matrix: DMatrix<f64>) -> Result<Self, LocateError> {
        let n = entries.len();
        let invalid = |reason: String| Err(LocateError::InvalidCovariance { reason });
        if matrix.nrows() != n || matrix.ncols() != n {
            return invalid(format!(
                "the matrix is {} x {} for {n} parameters; expected {n} x {n}",
                matrix.nrows(),
                matrix.ncols()
            ));
        }
        for (i, e) in entries.iter().enumerate() {
            if entries[..i].contains(e) {
                return invalid(format!("parameter '{}' appears twice", e.name()));
            }
        }
        if matrix.iter().any(|v| !v.is_finite()) {
            return invalid("the matrix holds a non-finite value".into());
        }
        for i in 0..n {
            if matrix[(i, i)] < 0.0 {
                return invalid(format!(
                    "the variance of '{}' is negative ({})",
                    entries[i].name(),
                    matrix[(i, i)]
                ));
            }
            for j in 0..i {
                let (a, b) = (matrix[(i, j)], matrix[(j, i)]);
                if (a - b).abs() > 1e-9 * a.abs().max(b.abs()) {
                    return invalid(format!("the matrix is not symmetric at ({i}, {j})"));
                }
            }
        }
        let matrix = (&matrix + matrix.transpose()) * 0.5;
        Ok(Self { entries, matrix })
    }

    /// The covariance of model parameters only (e.g. a
    /// `psdcal_calib::Covariance`'s `params` and `matrix`).
    pub fn from_params(params: &[Param], matrix: &DMatrix<f64>) -> Result<Self, LocateError> {
        Self::new(
            params.iter().copied().map(Estimated::Model).collect(),
            matrix.clone(),
        )
    }

    /// A covariance of parameters given by name (`f`, `cx`, …, `g_x2`, …),
    /// e.g. a calibration's.
    pub fn from_names<S: AsRef<str>>(
        names: &[S],
        matrix: &DMatrix<f64>,
    ) -> Result<Self, LocateError> {
        let entries = names
            .iter()
            .map(|n| Estimated::parse(n.as_ref()))
            .collect::<Result<Vec<_>, _>>()?;
        Self::new(entries, matrix.clone())
    }

    /// The covariance as calibration.json stores it: names (`f`, `cx`, …,
    /// `g_x2`, …) and rows.
    ///
    /// ```
    /// use psdcal_locate::ParameterCovariance;
    ///
    /// let cov = ParameterCovariance::from_named(
    ///     &["f", "cx"],
    ///     &[vec![1e-4, 0.0], vec![0.0, 4e-6]],
    /// )
    /// .unwrap();
    /// assert_eq!(cov.len(), 2);
    /// assert!(ParameterCovariance::from_named(&["zoom"], &[vec![1.0]]).is_err());
    /// ```
    pub fn from_named<S: AsRef<str>>(names: &[S], rows: &[Vec<f64>]) -> Result<Self, LocateError> {
        let entries = names
            .iter()
            .map(|n| Estimated::parse(n.as_ref()))
            .collect::<Result<Vec<_>, _>>()?;
        let n = entries.len();
        if rows.len() != n || rows.iter().any(|r| r.len() != n) {
            return Err(LocateError::InvalidCovariance {
                reason: format!("expected {n} rows of {n} entries"),
            });
        }
        Self::new(entries, DMatrix::from_fn(n, n, |i, j| rows[i][j]))
    }

    /// The estimated quantities, in matrix order.
    pub fn entries(&self) -> &[Estimated] {
        &self.entries
    }

    /// The matrix.
    pub fn matrix(&self) -> &DMatrix<f64> {
        &self.matrix
    }

    /// Number of estimated quantities.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether nothing was estimated.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Whether the relative channel gains are among the estimated quantities.
    pub fn has_gains(&self) -> bool {
        self.entries.iter().any(|e| matches!(e, Estimated::Gain(_)))
    }

    /// Standard deviation of one quantity (`None` when it was not estimated).
    pub fn std(&self, e: Estimated) -> Option<f64> {
        let k = self.entries.iter().position(|x| *x == e)?;
        Some(self.matrix[(k, k)].max(0.0).sqrt())
    }

    /// The covariance scaled by `k²` (k-σ bounds).
    pub fn scaled(&self, k: f64) -> Self {
        Self {
            entries: self.entries.clone(),
            matrix: &self.matrix * (k * k),
        }
    }

    /// `J Σ Jᵀ` for a 2-vector with Jacobian `wrt_model` (2×11, Param::ALL
    /// order) and, when the point came from amplitudes, `wrt_gains` (2×3,
    /// `g_x2, g_y1, g_y2`). Without `wrt_gains` the gains' entries do not
    /// contribute.
    pub fn propagate(
        &self,
        wrt_model: &SMatrix<f64, 2, N_PARAMS>,
        wrt_gains: Option<&Matrix2x3<f64>>,
    ) -> Matrix2<f64> {
        let n = self.entries.len();
        let mut j = DMatrix::<f64>::zeros(2, n);
        for (c, e) in self.entries.iter().enumerate() {
            match (e, wrt_gains) {
                (Estimated::Model(p), _) => {
                    j.set_column(c, &wrt_model.column(p.index()));
                }
                (Estimated::Gain(k), Some(g)) if *k < 3 => {
                    j.set_column(c, &g.column(*k));
                }
                _ => {}
            }
        }
        let out = &j * &self.matrix * j.transpose();
        let m = Matrix2::new(out[(0, 0)], out[(0, 1)], out[(1, 0)], out[(1, 1)]);
        (m + m.transpose()) * 0.5
    }
}

/// `σ² J Jᵀ`: the covariance of a 2-vector with Jacobian `j` with respect to
/// a point with independent noise of standard deviation `sigma` per
/// coordinate.
pub fn point_noise_covariance(j: &Matrix2<f64>, sigma: f64) -> Matrix2<f64> {
    j * j.transpose() * (sigma * sigma)
}

/// `(σx, σy, ρ)` of a 2×2 covariance: the standard deviations and the
/// correlation (0 when a σ is 0).
pub fn sigmas_and_correlation(cov: &Matrix2<f64>) -> (f64, f64, f64) {
    let sx = cov[(0, 0)].max(0.0).sqrt();
    let sy = cov[(1, 1)].max(0.0).sqrt();
    let rho = if sx > 0.0 && sy > 0.0 {
        (cov[(0, 1)] / (sx * sy)).clamp(-1.0, 1.0)
    } else {
        0.0
    };
    (sx, sy, rho)
}
