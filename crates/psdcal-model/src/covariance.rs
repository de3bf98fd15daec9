//! [`ParameterCovariance`]: the one covariance type of psdcal — a symmetric
//! matrix over named model parameters (docs/model.md §4.6, §5).
//!
//! The names are those of the model's flat parameter vector
//! ([`crate::Model::names`]: `f`, `cx`, …, `l2`, another stage's
//! coefficients, `g_x2`, `g_y1`, `g_y2`), so a covariance over any parameter
//! of any chain can be stored, read back and propagated: a user resolves
//! each name with [`crate::Model::index`]. Calibration's fit covariance
//! holds one (with its pose blocks, σ² and degrees of freedom), a
//! calibration.json record converts to and from one, and the location crate
//! propagates one to rays and positions.
//!
//! The matrix is validated once, here ([`ParameterCovariance::new`]): square
//! for its names, no name twice, finite, symmetric to a relative 1e-9 and
//! with non-negative variances; it is stored symmetrised. The failure is a
//! [`CovarianceError`] that says where, so a file reader can phrase it with
//! the file's own field names.

use nalgebra::DMatrix;

use crate::params::Param;

/// Relative tolerance of the symmetry check.
pub const SYMMETRY_TOLERANCE: f64 = 1e-9;

/// Why a matrix is not a covariance of its names. Indices are 0-based.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CovarianceError {
    /// The matrix does not have one row per name.
    #[error("the matrix is {rows} x {cols} for {names} parameters; expected {names} x {names}")]
    Shape {
        /// Rows found.
        rows: usize,
        /// Columns found (of the first short or long row, for rows).
        cols: usize,
        /// Number of names.
        names: usize,
    },
    /// One row (of a matrix given as rows) has the wrong length.
    #[error("row {row} has {len} entries; expected {names} rows of {names} entries")]
    RowLength {
        /// The row.
        row: usize,
        /// Its length.
        len: usize,
        /// Number of names.
        names: usize,
    },
    /// A name appears twice.
    #[error("parameter '{name}' appears twice")]
    Duplicate {
        /// The name.
        name: String,
    },
    /// An entry is NaN or infinite.
    #[error("the matrix holds a non-finite value at ({row}, {col})")]
    NonFinite {
        /// Its row.
        row: usize,
        /// Its column.
        col: usize,
    },
    /// `M[row][col]` and `M[col][row]` differ beyond rounding (`col < row`).
    #[error("the matrix is not symmetric at ({row}, {col}): {value} but {mirror}")]
    Asymmetric {
        /// The row.
        row: usize,
        /// The column.
        col: usize,
        /// `M[row][col]`.
        value: f64,
        /// `M[col][row]`.
        mirror: f64,
    },
    /// A variance is negative.
    #[error("the variance of '{name}' is negative ({value})")]
    NegativeVariance {
        /// Its index.
        index: usize,
        /// Its name.
        name: String,
        /// The variance.
        value: f64,
    },
    /// A cross-covariance block does not match the two name sets.
    #[error("the cross-covariance is {rows} x {cols}; expected {expected_rows} x {expected_cols}")]
    CrossShape {
        /// Rows found.
        rows: usize,
        /// Columns found.
        cols: usize,
        /// Rows expected (the second set's names).
        expected_rows: usize,
        /// Columns expected (the first set's names).
        expected_cols: usize,
    },
    /// A name is not in the set asked for (sub-blocks).
    #[error("the covariance has no parameter '{name}' (it has {available})")]
    UnknownName {
        /// The name.
        name: String,
        /// The names it has, comma separated.
        available: String,
    },
}

/// A covariance over named parameters: `names[i]` is row and column `i`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParameterCovariance {
    names: Vec<String>,
    matrix: DMatrix<f64>,
}

impl ParameterCovariance {
    /// No uncertainty (nothing estimated).
    pub fn none() -> Self {
        Self::default()
    }

    /// A covariance of `names`; the matrix must be square for them, finite,
    /// symmetric (relative [`SYMMETRY_TOLERANCE`]) with a non-negative
    /// diagonal, and no name may appear twice. It is stored symmetrised.
    ///
    /// ```
    /// use nalgebra::DMatrix;
    /// use psdcal_model::covariance::ParameterCovariance;
    ///
    /// let cov = ParameterCovariance::new(
    ///     vec!["f".into(), "cx".into()],
    ///     DMatrix::from_row_slice(2, 2, &[4e-6, 1e-7, 1e-7, 1e-6]),
    /// )
    /// .unwrap();
    /// assert_eq!(cov.std("f"), Some(2e-3));
    /// assert!((cov.correlation()[(0, 1)] - 0.05).abs() < 1e-15);
    /// assert!(ParameterCovariance::new(vec!["f".into()], DMatrix::from_element(1, 1, -1.0)).is_err());
    /// ```
    pub fn new(names: Vec<String>, matrix: DMatrix<f64>) -> Result<Self, CovarianceError> {
        let n = names.len();
        if matrix.nrows() != n || matrix.ncols() != n {
            return Err(CovarianceError::Shape {
                rows: matrix.nrows(),
                cols: matrix.ncols(),
                names: n,
            });
        }
        for (i, name) in names.iter().enumerate() {
            if names[..i].contains(name) {
                return Err(CovarianceError::Duplicate { name: name.clone() });
            }
        }
        for i in 0..n {
            for j in 0..n {
                if !matrix[(i, j)].is_finite() {
                    return Err(CovarianceError::NonFinite { row: i, col: j });
                }
            }
        }
        for i in 0..n {
            for j in 0..i {
                let (a, b) = (matrix[(i, j)], matrix[(j, i)]);
                if (a - b).abs() > SYMMETRY_TOLERANCE * a.abs().max(b.abs()) {
                    return Err(CovarianceError::Asymmetric {
                        row: i,
                        col: j,
                        value: a,
                        mirror: b,
                    });
                }
            }
            if matrix[(i, i)] < 0.0 {
                return Err(CovarianceError::NegativeVariance {
                    index: i,
                    name: names[i].clone(),
                    value: matrix[(i, i)],
                });
            }
        }
        let matrix = (&matrix + matrix.transpose()) * 0.5;
        Ok(Self { names, matrix })
    }

    /// A covariance given as rows (one per name, as calibration.json stores
    /// it); the rows are checked for shape first, then as [`Self::new`].
    ///
    /// ```
    /// use psdcal_model::covariance::ParameterCovariance;
    ///
    /// let cov = ParameterCovariance::from_named(&["f", "cx"], &[vec![1e-4, 0.0], vec![0.0, 4e-6]]).unwrap();
    /// assert_eq!(cov.len(), 2);
    /// assert!(ParameterCovariance::from_named(&["f"], &[vec![1.0, 2.0]]).is_err());
    /// ```
    pub fn from_named<S: AsRef<str>>(
        names: &[S],
        rows: &[Vec<f64>],
    ) -> Result<Self, CovarianceError> {
        let n = names.len();
        if rows.len() != n {
            return Err(CovarianceError::Shape {
                rows: rows.len(),
                cols: rows.first().map_or(0, Vec::len),
                names: n,
            });
        }
        if let Some((row, r)) = rows.iter().enumerate().find(|(_, r)| r.len() != n) {
            return Err(CovarianceError::RowLength {
                row,
                len: r.len(),
                names: n,
            });
        }
        Self::new(
            names.iter().map(|s| s.as_ref().to_string()).collect(),
            DMatrix::from_fn(n, n, |i, j| rows[i][j]),
        )
    }

    /// A covariance of standard parameters ([`Param`] names).
    pub fn from_params(params: &[Param], matrix: &DMatrix<f64>) -> Result<Self, CovarianceError> {
        Self::new(
            params.iter().map(|p| p.name().to_string()).collect(),
            matrix.clone(),
        )
    }

    /// The names, in matrix order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The (symmetric) matrix.
    pub fn matrix(&self) -> &DMatrix<f64> {
        &self.matrix
    }

    /// The matrix as rows (calibration.json's form).
    pub fn rows(&self) -> Vec<Vec<f64>> {
        self.matrix
            .row_iter()
            .map(|r| r.iter().copied().collect())
            .collect()
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Whether nothing was estimated.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Row of a parameter.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Whether a parameter is among the estimated ones.
    pub fn contains(&self, name: &str) -> bool {
        self.index(name).is_some()
    }

    /// The entry of parameters `a` and `b`.
    pub fn get(&self, a: &str, b: &str) -> Option<f64> {
        Some(self.matrix[(self.index(a)?, self.index(b)?)])
    }

    /// Standard deviation of a parameter (`None` when it was not estimated);
    /// by name or [`Param`].
    pub fn std(&self, name: impl AsRef<str>) -> Option<f64> {
        let k = self.index(name.as_ref())?;
        Some(self.matrix[(k, k)].max(0.0).sqrt())
    }

    /// The correlation matrix (0 where a variance is 0).
    pub fn correlation(&self) -> DMatrix<f64> {
        let n = self.matrix.nrows();
        DMatrix::from_fn(n, n, |i, j| {
            let d = (self.matrix[(i, i)] * self.matrix[(j, j)]).sqrt();
            if d > 0.0 {
                self.matrix[(i, j)] / d
            } else {
                0.0
            }
        })
    }

    /// The covariance of a subset of the parameters, in the order given.
    pub fn sub<S: AsRef<str>>(&self, names: &[S]) -> Result<Self, CovarianceError> {
        let rows = names
            .iter()
            .map(|n| {
                self.index(n.as_ref())
                    .ok_or_else(|| CovarianceError::UnknownName {
                        name: n.as_ref().to_string(),
                        available: self.names.join(", "),
                    })
            })
            .collect::<Result<Vec<usize>, _>>()?;
        Self::new(
            names.iter().map(|n| n.as_ref().to_string()).collect(),
            DMatrix::from_fn(rows.len(), rows.len(), |i, j| {
                self.matrix[(rows[i], rows[j])]
            }),
        )
    }

    /// The block `Cov(a, b)` between the parameters `rows` and `cols`
    /// (`rows.len() × cols.len()`), by name.
    pub fn cross<S: AsRef<str>>(
        &self,
        rows: &[S],
        cols: &[S],
    ) -> Result<DMatrix<f64>, CovarianceError> {
        let index = |names: &[S]| {
            names
                .iter()
                .map(|n| {
                    self.index(n.as_ref())
                        .ok_or_else(|| CovarianceError::UnknownName {
                            name: n.as_ref().to_string(),
                            available: self.names.join(", "),
                        })
                })
                .collect::<Result<Vec<usize>, _>>()
        };
        let (r, c) = (index(rows)?, index(cols)?);
        Ok(DMatrix::from_fn(r.len(), c.len(), |i, j| {
            self.matrix[(r[i], c[j])]
        }))
    }

    /// The joint covariance of `self`'s parameters and `other`'s (names
    /// disjoint), `[[Σ_a, Cᵀ], [C, Σ_b]]` with `cross = C = Cov(b, a)`
    /// (`other.len() × self.len()`); the inverse of [`Self::sub`] and
    /// [`Self::cross`] on the two name sets.
    pub fn joint(&self, other: &Self, cross: &DMatrix<f64>) -> Result<Self, CovarianceError> {
        let (na, nb) = (self.len(), other.len());
        if cross.shape() != (nb, na) {
            return Err(CovarianceError::CrossShape {
                rows: cross.nrows(),
                cols: cross.ncols(),
                expected_rows: nb,
                expected_cols: na,
            });
        }
        let mut matrix = DMatrix::zeros(na + nb, na + nb);
        matrix.view_mut((0, 0), (na, na)).copy_from(&self.matrix);
        matrix.view_mut((na, na), (nb, nb)).copy_from(&other.matrix);
        for i in 0..nb {
            for j in 0..na {
                let v = cross[(i, j)];
                matrix[(na + i, j)] = v;
                matrix[(j, na + i)] = v;
            }
        }
        let names = self.names.iter().chain(&other.names).cloned().collect();
        Self::new(names, matrix)
    }

    /// The covariance scaled by `k²` (k-σ bounds).
    pub fn scaled(&self, k: f64) -> Self {
        Self {
            names: self.names.clone(),
            matrix: &self.matrix * (k * k),
        }
    }

    /// `J Σ Jᵀ` for a quantity whose Jacobian with respect to parameter
    /// `names()[i]` is column `columns[i]` of `jacobian` (`None`: the
    /// quantity does not depend on it). `jacobian` is `d × P`.
    pub fn propagate_columns(
        &self,
        jacobian: &DMatrix<f64>,
        columns: &[Option<usize>],
    ) -> DMatrix<f64> {
        let d = jacobian.nrows();
        let mut j = DMatrix::<f64>::zeros(d, self.len());
        for (c, col) in columns.iter().enumerate().take(self.len()) {
            if let Some(k) = col {
                j.set_column(c, &jacobian.column(*k));
            }
        }
        let out = &j * &self.matrix * j.transpose();
        (&out + out.transpose()) * 0.5
    }
}
