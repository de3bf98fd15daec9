//! Plane-to-sensor homographies by the direct linear transformation, with
//! Hartley's data normalisation (docs/model.md §4.2–4.3; the paper's (P17), (P18)
//! and (P36)–(P38)).
//!
//! A template point `(X, Y, 0)` and its image point `(x, y)` (both mm) are
//! related, for a pinhole, by (P17)–(P18):
//!
//! ```text
//! s (x, y, 1)ᵀ = H (X, Y, 1)ᵀ,     H = A [r1 r2 t]   (up to scale)
//! ```
//!
//! Each correspondence gives two rows of the DLT system `L h = 0`
//! (`h` = the nine entries of `H`, row-major):
//!
//! ```text
//! [ X  Y  1  0  0  0  −xX  −xY  −x ]
//! [ 0  0  0  X  Y  1  −yX  −yY  −y ]
//! ```
//!
//! and `h` is the right singular vector of `L` for its smallest singular
//! value. The system is padded with zero rows to at least 9 × 9 (a thin SVD of
//! an 8 × 9 matrix would drop the null vector) and the smallest singular value
//! is picked explicitly.
//!
//! *Normalisation* (P36)–(P38), on by default: each point set is translated to
//! its centroid and scaled isotropically to a mean distance of √2 from the
//! origin (`T_Q` for the image, `T_P` for the template); the DLT gives `M°`
//! with `T_Q q ≃ M° T_P p`, and `H = T_Q⁻¹ M° T_P`.
//!
//! *Convention*: a returned [`Homography`] has unit Frobenius norm and
//! `H[(2,2)] ≥ 0` (for a template whose origin is in front of the sensor,
//! `H[(2,2)] ∝ t_z > 0`); if `H[(2,2)]` is exactly zero, the first non-zero
//! entry in row-major order is made positive.
//!
//! *Degeneracy*: fewer than 4 points, collinear template or image points
//! (checked on the normalised coordinates: the smaller principal spread below
//! 1e-9 of the larger), or a rank-deficient DLT system (second-smallest
//! singular value below [`RANK_TOLERANCE`] of the largest, judged on the
//! normalised system whatever the option) are refused with a typed error.

use nalgebra::{DMatrix, DVector, Matrix3, SMatrix, SVector, Vector2, Vector3};

use crate::CalibError;

/// Relative size (second-smallest / largest singular value of the normalised
/// DLT system) below which the point configuration is declared degenerate.
pub const RANK_TOLERANCE: f64 = 1e-10;

/// Ratio of the smaller to the larger principal spread (standard deviation)
/// below which a point set counts as collinear.
pub const COLLINEAR_TOLERANCE: f64 = 1e-9;

/// Iteration budget handed to nalgebra's SVD (it never loops forever).
const SVD_MAX_ITERATIONS: usize = 10_000;

/// A plane-to-sensor homography: maps template `(X, Y, 1)` to image
/// `(x, y, 1)` up to scale (mm on both sides).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Homography {
    matrix: Matrix3<f64>,
}

impl Homography {
    /// A homography from a 3 × 3 matrix, normalised to unit Frobenius norm with
    /// `H[(2,2)] ≥ 0`. Refuses non-finite or singular matrices.
    pub fn from_matrix(matrix: Matrix3<f64>) -> Result<Self, CalibError> {
        if !matrix.iter().all(|v| v.is_finite()) {
            return Err(CalibError::Numerical {
                stage: "homography",
                reason: "matrix has non-finite entries".into(),
            });
        }
        let norm = matrix.norm();
        if norm == 0.0 {
            return Err(CalibError::Numerical {
                stage: "homography",
                reason: "matrix is zero".into(),
            });
        }
        let mut m = matrix / norm;
        let pivot = if m[(2, 2)] != 0.0 {
            m[(2, 2)]
        } else {
            // Row-major scan (nalgebra stores column-major).
            (0..9)
                .map(|k| m[(k / 3, k % 3)])
                .find(|v| *v != 0.0)
                .unwrap_or(1.0)
        };
        if pivot < 0.0 {
            m = -m;
        }
        if m.determinant().abs() <= 1e-14 {
            return Err(CalibError::Degenerate {
                reason: format!(
                    "homography is singular (|det| = {:.3e} at unit norm): the template plane is \
                     seen edge-on or the points are degenerate",
                    m.determinant().abs()
                ),
            });
        }
        Ok(Self { matrix: m })
    }

    /// The normalised matrix.
    pub fn matrix(&self) -> &Matrix3<f64> {
        &self.matrix
    }

    /// Column `i` (0, 1, 2) of the matrix: `h1`, `h2`, `h3` of (P26)–(P28).
    pub fn column(&self, i: usize) -> Vector3<f64> {
        self.matrix.column(i).into_owned()
    }

    /// Image point of a template point. Fails when the point maps to
    /// infinity (it lies on the template's vanishing line).
    pub fn apply(&self, template_xy: &Vector2<f64>) -> Result<Vector2<f64>, CalibError> {
        let q = self.matrix * Vector3::new(template_xy.x, template_xy.y, 1.0);
        let scale = self.matrix.row(2).norm() * (1.0 + template_xy.norm());
        if q.z.is_nan() || q.z.abs() <= 1e-14 * scale {
            return Err(CalibError::Numerical {
                stage: "homography",
                reason: format!(
                    "template point ({:.6}, {:.6}) maps to infinity",
                    template_xy.x, template_xy.y
                ),
            });
        }
        let p = Vector2::new(q.x / q.z, q.y / q.z);
        if p.x.is_finite() && p.y.is_finite() {
            Ok(p)
        } else {
            Err(CalibError::Numerical {
                stage: "homography",
                reason: "non-finite image point".into(),
            })
        }
    }

    /// Root-mean-square transfer error `‖H(P_j) − q_j‖` in the image, mm.
    pub fn rms_transfer_error(
        &self,
        template: &[Vector2<f64>],
        image: &[Vector2<f64>],
    ) -> Result<f64, CalibError> {
        check_pairs(template, image, 1)?;
        let mut sum = 0.0;
        for (p, q) in template.iter().zip(image) {
            sum += (self.apply(p)? - q).norm_squared();
        }
        Ok((sum / template.len() as f64).sqrt())
    }
}

/// Options of [`fit_homography`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HomographyOptions {
    /// Hartley normalisation (P36)–(P38). Default `true`.
    pub normalize: bool,
}

impl Default for HomographyOptions {
    fn default() -> Self {
        Self { normalize: true }
    }
}

/// The result of a DLT fit and what it took.
#[derive(Debug, Clone, PartialEq)]
pub struct HomographyFit {
    /// The homography.
    pub homography: Homography,
    /// RMS transfer error in the image, mm.
    pub rms: f64,
    /// Whether Hartley normalisation was used for the solve.
    pub normalized: bool,
    /// Number of correspondences.
    pub points: usize,
    /// Singular values of the (normalised) DLT system, descending (9).
    pub singular_values: Vec<f64>,
    /// Second-smallest over largest singular value of the normalised system:
    /// how far the configuration is from degenerate (compare with
    /// [`RANK_TOLERANCE`]).
    pub conditioning: f64,
}

/// A right null vector with the singular values it was chosen from.
pub(crate) struct NullVector {
    /// Unit right singular vector of the smallest singular value.
    pub vector: DVector<f64>,
    /// All singular values, descending.
    pub singular_values: Vec<f64>,
}

/// Right singular vector of the smallest singular value of `a`, padding `a`
/// with zero rows to at least square so that the thin SVD keeps the null
/// space. The smallest singular value is selected explicitly.
pub(crate) fn null_vector(a: &DMatrix<f64>, stage: &'static str) -> Result<NullVector, CalibError> {
    if !a.iter().all(|v| v.is_finite()) {
        return Err(CalibError::Numerical {
            stage,
            reason: "system matrix has non-finite entries".into(),
        });
    }
    let n = a.ncols();
    // The thin SVD of a wide system (8 × 9) drops the null vector: pad it
    // with zero rows to square.
    let rows = a.nrows().max(n);
    let mut square = DMatrix::zeros(rows, n);
    square.view_mut((0, 0), (a.nrows(), n)).copy_from(a);
    let svd = nalgebra::linalg::SVD::try_new(square, false, true, f64::EPSILON, SVD_MAX_ITERATIONS)
        .ok_or_else(|| CalibError::Numerical {
            stage,
            reason: "SVD did not converge".into(),
        })?;
    let v_t = svd.v_t.as_ref().ok_or_else(|| CalibError::Numerical {
        stage,
        reason: "SVD returned no right singular vectors".into(),
    })?;
    let sv = &svd.singular_values;
    let imin = (0..sv.len())
        .min_by(|&i, &j| sv[i].total_cmp(&sv[j]))
        .ok_or_else(|| CalibError::Numerical {
            stage,
            reason: "empty SVD".into(),
        })?;
    let vector = v_t.row(imin).transpose();
    let mut singular_values: Vec<f64> = sv.iter().copied().collect();
    singular_values.sort_by(|a, b| b.total_cmp(a));
    if !vector.iter().all(|v| v.is_finite()) {
        return Err(CalibError::Numerical {
            stage,
            reason: "null vector has non-finite entries".into(),
        });
    }
    Ok(NullVector {
        vector,
        singular_values,
    })
}

/// Hartley's normalising similarity of a point set (P37): translates the
/// centroid to the origin and scales isotropically to a mean distance of √2.
/// Fails for an empty set, non-finite points or all points coincident.
pub fn normalizing_transform(points: &[Vector2<f64>]) -> Result<Matrix3<f64>, CalibError> {
    if points.is_empty() {
        return Err(CalibError::InvalidInput {
            reason: "empty point set".into(),
        });
    }
    if !points.iter().all(|p| p.x.is_finite() && p.y.is_finite()) {
        return Err(CalibError::InvalidInput {
            reason: "non-finite point coordinates".into(),
        });
    }
    let n = points.len() as f64;
    let centroid = points.iter().fold(Vector2::zeros(), |acc, p| acc + p) / n;
    let mean_dist = points.iter().map(|p| (p - centroid).norm()).sum::<f64>() / n;
    if !mean_dist.is_finite() || mean_dist <= 0.0 {
        return Err(CalibError::Degenerate {
            reason: "all points coincide".into(),
        });
    }
    let s = std::f64::consts::SQRT_2 / mean_dist;
    Ok(Matrix3::new(
        s,
        0.0,
        -s * centroid.x,
        0.0,
        s,
        -s * centroid.y,
        0.0,
        0.0,
        1.0,
    ))
}

fn transform_points(t: &Matrix3<f64>, points: &[Vector2<f64>]) -> Vec<Vector2<f64>> {
    points
        .iter()
        .map(|p| Vector2::new(t[(0, 0)] * p.x + t[(0, 2)], t[(1, 1)] * p.y + t[(1, 2)]))
        .collect()
}

/// Ratio of the smaller to the larger principal standard deviation of a
/// point set (0 for collinear points).
pub(crate) fn spread_ratio(points: &[Vector2<f64>]) -> f64 {
    let n = points.len() as f64;
    let c = points.iter().fold(Vector2::zeros(), |acc, p| acc + p) / n;
    let (mut a, mut b, mut d) = (0.0, 0.0, 0.0);
    for p in points {
        let v = p - c;
        a += v.x * v.x;
        b += v.x * v.y;
        d += v.y * v.y;
    }
    let mean = 0.5 * (a + d);
    let dev = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (lmax, lmin) = (mean + dev, (mean - dev).max(0.0));
    if lmax > 0.0 {
        (lmin / lmax).sqrt()
    } else {
        0.0
    }
}

fn check_pairs(
    template: &[Vector2<f64>],
    image: &[Vector2<f64>],
    min: usize,
) -> Result<(), CalibError> {
    if template.len() != image.len() {
        return Err(CalibError::InvalidInput {
            reason: format!(
                "{} template points but {} image points",
                template.len(),
                image.len()
            ),
        });
    }
    if template.len() < min {
        return Err(CalibError::TooFewPoints {
            image: String::new(),
            points: template.len(),
        });
    }
    if !template
        .iter()
        .chain(image)
        .all(|p| p.x.is_finite() && p.y.is_finite())
    {
        return Err(CalibError::InvalidInput {
            reason: "non-finite point coordinates".into(),
        });
    }
    Ok(())
}

/// The DLT system (P17)–(P18) of point pairs.
fn dlt_system(template: &[Vector2<f64>], image: &[Vector2<f64>]) -> DMatrix<f64> {
    let mut l = DMatrix::zeros(2 * template.len(), 9);
    for (k, (p, q)) in template.iter().zip(image).enumerate() {
        let (xx, yy, x, y) = (p.x, p.y, q.x, q.y);
        let r0 = [xx, yy, 1.0, 0.0, 0.0, 0.0, -x * xx, -x * yy, -x];
        let r1 = [0.0, 0.0, 0.0, xx, yy, 1.0, -y * xx, -y * yy, -y];
        for j in 0..9 {
            l[(2 * k, j)] = r0[j];
            l[(2 * k + 1, j)] = r1[j];
        }
    }
    l
}

/// Smallest eigenvalue ratio `λ₂/λ₁` of the normal matrix (second-smallest
/// over largest) below which [`normal_null_vector`] defers to the SVD: its
/// eigenvalues carry an absolute error of about `ε λ₁`, so a ratio near
/// rounding (a nearly degenerate system) is judged on the SVD of `A`.
const NORMAL_EIGEN_FLOOR: f64 = 1e-8;

/// The null vector and singular values of the normalised DLT system `A`
/// from the eigen-decomposition of its 9 × 9 normal matrix `M = AᵀA`
/// (`σ_k = √λ_k`), accumulated row by row without forming `A`. In
/// normalised coordinates the second-smallest singular value of ≥ 4 points
/// in general position is of order one, so squaring the condition costs
/// nothing: the eigenvector of the smallest eigenvalue is the null vector
/// to rounding (measured against the SVD in this module's tests). `None`
/// when the system is nearly degenerate (the SVD then decides).
fn normal_null_vector(template: &[Vector2<f64>], image: &[Vector2<f64>]) -> Option<NullVector> {
    let m = normal_matrix(template.iter().copied().zip(image.iter().copied()));
    if !m.iter().all(|v| v.is_finite()) {
        return None;
    }
    let eigen = m.symmetric_eigen();
    let mut order: Vec<usize> = (0..9).collect();
    order.sort_by(|&i, &j| eigen.eigenvalues[j].total_cmp(&eigen.eigenvalues[i]));
    let largest = eigen.eigenvalues[order[0]];
    if !(largest > 0.0 && eigen.eigenvalues[order[7]] > NORMAL_EIGEN_FLOOR * largest) {
        return None;
    }
    let vector = DVector::from_iterator(9, eigen.eigenvectors.column(order[8]).iter().copied());
    let singular_values = order
        .iter()
        .map(|&k| eigen.eigenvalues[k].max(0.0).sqrt())
        .collect();
    Some(NullVector {
        vector,
        singular_values,
    })
}

/// `M = AᵀA` of the DLT system (P17)–(P18) of normalised pairs
/// `(template, image)`, accumulated row by row without forming `A`.
fn normal_matrix(pairs: impl Iterator<Item = (Vector2<f64>, Vector2<f64>)>) -> SMatrix<f64, 9, 9> {
    let mut m = SMatrix::<f64, 9, 9>::zeros();
    for (p, q) in pairs {
        let (xx, yy, x, y) = (p.x, p.y, q.x, q.y);
        let r0 = SVector::<f64, 9>::from([xx, yy, 1.0, 0.0, 0.0, 0.0, -x * xx, -x * yy, -x]);
        let r1 = SVector::<f64, 9>::from([0.0, 0.0, 0.0, xx, yy, 1.0, -y * xx, -y * yy, -y]);
        m.ger(1.0, &r0, &r0, 1.0);
        m.ger(1.0, &r1, &r1, 1.0);
    }
    m
}

fn matrix_of(h: &DVector<f64>) -> Matrix3<f64> {
    Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8])
}

/// Fits the homography taking `template` points to `image` points by DLT
/// (P17)–(P18), with Hartley normalisation (P36)–(P38) unless switched off.
///
/// Errors: [`CalibError::TooFewPoints`] (with an empty image id; callers
/// that know the image fill it in) for fewer than 4 pairs,
/// [`CalibError::InvalidInput`] for mismatched lengths or non-finite points,
/// [`CalibError::Degenerate`] for collinear or otherwise rank-deficient
/// configurations.
pub fn fit_homography(
    template: &[Vector2<f64>],
    image: &[Vector2<f64>],
    options: &HomographyOptions,
) -> Result<HomographyFit, CalibError> {
    check_pairs(template, image, 4)?;
    let t_p = normalizing_transform(template).map_err(|e| rename_degenerate(e, "template"))?;
    let t_q = normalizing_transform(image).map_err(|e| rename_degenerate(e, "image"))?;
    let p_n = transform_points(&t_p, template);
    let q_n = transform_points(&t_q, image);
    for (name, pts) in [("template", &p_n), ("image", &q_n)] {
        let ratio = spread_ratio(pts);
        if ratio.is_nan() || ratio <= COLLINEAR_TOLERANCE {
            return Err(CalibError::Degenerate {
                reason: format!(
                    "the {name} points are collinear (principal spread ratio {ratio:.2e}): a \
                     homography needs at least 4 points, no 3 of them on one line, not all on one line"
                ),
            });
        }
    }
    let normalized_solution = match normal_null_vector(&p_n, &q_n) {
        Some(solution) => solution,
        None => null_vector(&dlt_system(&p_n, &q_n), "homography")?,
    };
    let sv = &normalized_solution.singular_values;
    let conditioning = if sv[0] > 0.0 {
        sv[sv.len() - 2] / sv[0]
    } else {
        0.0
    };
    if conditioning.is_nan() || conditioning <= RANK_TOLERANCE {
        return Err(CalibError::Degenerate {
            reason: format!(
                "the homography is not determined by these {} points (DLT second-smallest/largest \
                 singular value {conditioning:.2e}): too many of them are collinear or coincident",
                template.len()
            ),
        });
    }
    let h = if options.normalize {
        let m0 = matrix_of(&normalized_solution.vector);
        let t_q_inv = t_q.try_inverse().ok_or_else(|| CalibError::Numerical {
            stage: "homography",
            reason: "image normalisation is singular".into(),
        })?;
        t_q_inv * m0 * t_p
    } else {
        matrix_of(&null_vector(&dlt_system(template, image), "homography")?.vector)
    };
    let homography = Homography::from_matrix(h)?;
    let rms = homography.rms_transfer_error(template, image)?;
    Ok(HomographyFit {
        homography,
        rms,
        normalized: options.normalize,
        points: template.len(),
        singular_values: normalized_solution.singular_values,
        conditioning,
    })
}

/// The normalised DLT homography of an image whose points have already
/// passed [`fit_homography`]'s checks, for inner loops (the preliminary
/// correction's consistency cost evaluates it dozens of times per image).
/// The same system (P17)–(P18), (P36)–(P38); its null vector is found by
/// inverse iteration on the 9 × 9 normal matrix `M = AᵀA`, accumulated row
/// by row without forming `A`: each step `x ← M⁻¹ x` shrinks the other
/// directions by `σ_min²/σ_k²`. Squaring the condition is harmless here: in
/// normalised coordinates the second-smallest singular value of a template of
/// ≥ 4 points in general position is of order one, so the null vector is
/// accurate to rounding; a relative ridge of 1e-14 keeps the Cholesky factor
/// of an exact (noise-free) system finite.
pub(crate) fn fast_homography(
    template: &[Vector2<f64>],
    image: &[Vector2<f64>],
) -> Result<Homography, CalibError> {
    check_pairs(template, image, 4)?;
    let t_p = normalizing_transform(template)?;
    fast_homography_normalised(template, &t_p, image).map(|(h, _)| h)
}

/// [`fast_homography`] with the template's normalising transform `t_p`
/// given (a template fitted again and again, as by the preliminary
/// correction); also returns the image's normalising transform.
pub(crate) fn fast_homography_normalised(
    template: &[Vector2<f64>],
    t_p: &Matrix3<f64>,
    image: &[Vector2<f64>],
) -> Result<(Homography, Matrix3<f64>), CalibError> {
    check_pairs(template, image, 4)?;
    let t_q = normalizing_transform(image)?;
    // The normalising transforms scale and translate (transform_points),
    // applied on the fly.
    let normalised = |t: &Matrix3<f64>, p: &Vector2<f64>| {
        Vector2::new(t[(0, 0)] * p.x + t[(0, 2)], t[(1, 1)] * p.y + t[(1, 2)])
    };
    let mut m = normal_matrix(
        template
            .iter()
            .zip(image)
            .map(|(p, q)| (normalised(t_p, p), normalised(&t_q, q))),
    );
    let ridge = 1e-14 * m.trace().max(f64::MIN_POSITIVE);
    for k in 0..9 {
        m[(k, k)] += ridge;
    }
    let cholesky = m.cholesky().ok_or_else(|| CalibError::Numerical {
        stage: "homography",
        reason: "the normal matrix of the DLT is not positive definite".into(),
    })?;
    let mut x = SVector::<f64, 9>::from_element(1.0 / 3.0);
    for _ in 0..4 {
        let y = cholesky.solve(&x);
        let norm = y.norm();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(CalibError::Numerical {
                stage: "homography",
                reason: "inverse iteration failed".into(),
            });
        }
        x = y / norm;
    }
    let t_q_inv = t_q.try_inverse().ok_or_else(|| CalibError::Numerical {
        stage: "homography",
        reason: "image normalisation is singular".into(),
    })?;
    let h = Homography::from_matrix(t_q_inv * Matrix3::from_row_slice(x.as_slice()) * t_p)?;
    Ok((h, t_q))
}

fn rename_degenerate(e: CalibError, what: &str) -> CalibError {
    match e {
        CalibError::Degenerate { reason } => CalibError::Degenerate {
            reason: format!("{what} points: {reason}"),
        },
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalizing_transform_has_unit_properties() {
        let pts = [
            Vector2::new(1.0, 2.0),
            Vector2::new(5.0, -1.0),
            Vector2::new(-3.0, 7.0),
        ];
        let t = normalizing_transform(&pts).unwrap();
        let q = transform_points(&t, &pts);
        let c = q.iter().fold(Vector2::zeros(), |a, p| a + p) / 3.0;
        let d = q.iter().map(|p| p.norm()).sum::<f64>() / 3.0;
        assert!(c.norm() < 1e-15);
        assert!((d - std::f64::consts::SQRT_2).abs() < 1e-15);
    }

    #[test]
    fn null_vector_of_8x9_is_found() {
        // 4 generic pairs under a known homography: exactly determined.
        let h = Matrix3::new(2.0, 0.1, 3.0, -0.2, 1.5, -1.0, 1e-3, 2e-3, 1.0);
        let hom = Homography::from_matrix(h).unwrap();
        let tpl = [
            Vector2::new(0.0, 0.0),
            Vector2::new(10.0, 1.0),
            Vector2::new(2.0, 9.0),
            Vector2::new(11.0, 12.0),
        ];
        let img: Vec<_> = tpl.iter().map(|p| hom.apply(p).unwrap()).collect();
        for normalize in [true, false] {
            let fit = fit_homography(&tpl, &img, &HomographyOptions { normalize }).unwrap();
            assert!(
                (fit.homography.matrix() - hom.matrix()).norm() < 1e-12,
                "{normalize}"
            );
        }
    }

    /// A known homography, 14 template points in general position, their
    /// exact images and the images perturbed by ±0.05 mm (deterministic).
    type Pairs = (
        Homography,
        Vec<Vector2<f64>>,
        Vec<Vector2<f64>>,
        Vec<Vector2<f64>>,
    );
    fn pairs() -> Pairs {
        let h = Matrix3::new(1.2, 0.15, 0.4, -0.1, 0.9, -0.3, 0.02, -0.015, 1.0);
        let hom = Homography::from_matrix(h).unwrap();
        let tpl: Vec<_> = (0..14)
            .map(|k| {
                let t = k as f64;
                Vector2::new(40.0 * (1.3 * t).sin(), 35.0 * (0.7 * t + 0.4).cos())
            })
            .collect();
        let exact: Vec<_> = tpl.iter().map(|p| hom.apply(p).unwrap()).collect();
        let noisy: Vec<_> = exact
            .iter()
            .enumerate()
            .map(|(k, q)| q + 0.05 * Vector2::new((2.1 * k as f64).sin(), (3.7 * k as f64).cos()))
            .collect();
        (hom, tpl, exact, noisy)
    }

    #[test]
    fn fast_homography_equals_the_full_fit() {
        // Exact pairs: both recover the true homography. Perturbed pairs:
        // both are the least-squares null vector of the same normalised
        // system, so they agree far below the noise.
        let (hom, tpl, exact, noisy) = pairs();
        let fast = fast_homography(&tpl, &exact).unwrap();
        assert!((fast.matrix() - hom.matrix()).norm() < 1e-10);
        let fast = fast_homography(&tpl, &noisy).unwrap();
        let full = fit_homography(&tpl, &noisy, &HomographyOptions { normalize: true }).unwrap();
        let moved = (full.homography.matrix() - hom.matrix()).norm();
        assert!(moved > 1e-4, "the perturbation moves the fit ({moved:e})");
        assert!((fast.matrix() - full.homography.matrix()).norm() < 1e-9 * moved.max(1.0));
    }

    #[test]
    fn normal_eigen_null_vector_equals_the_svd() {
        // The same normalised, noisy system solved both ways: the null
        // vector (up to sign) and the singular values above the smallest
        // agree to rounding amplified by the squared condition (σ₁²/σ₂² is
        // below 1e3 here, so 1e-12); the smallest, √λ₉ of a noise-level λ₉,
        // to its absolute error √(ε λ₁).
        let (_, tpl, _, img) = pairs();
        let p_n = transform_points(&normalizing_transform(&tpl).unwrap(), &tpl);
        let q_n = transform_points(&normalizing_transform(&img).unwrap(), &img);
        let eigen = normal_null_vector(&p_n, &q_n).expect("well conditioned");
        let svd = null_vector(&dlt_system(&p_n, &q_n), "test").unwrap();
        let sign = eigen.vector.dot(&svd.vector).signum();
        assert!((eigen.vector.clone() * sign - &svd.vector).norm() < 1e-12);
        let s = &svd.singular_values;
        assert!(s[0] * s[0] / (s[7] * s[7]) < 1e3);
        for (e, v) in eigen.singular_values.iter().zip(s).take(8) {
            assert!((e - v).abs() < 1e-12 * s[0], "{e} against {v}");
        }
        assert!((eigen.singular_values[8] - s[8]).abs() < (f64::EPSILON * s[0] * s[0]).sqrt());
        // Collinear points: the eigen route declines, the SVD judges.
        let line: Vec<_> = (0..6)
            .map(|k| Vector2::new(k as f64, 2.0 * k as f64))
            .collect();
        assert!(normal_null_vector(&line, &line).is_none());
    }
}
