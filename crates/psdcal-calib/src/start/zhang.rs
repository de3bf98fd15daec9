//! The adapted Zhang closed form: intrinsics from homographies (docs/model.md §4.4,
//! the paper's (P19)–(P25) with its typos corrected) and a pose from one
//! homography (docs/model.md §4.5, (P26)–(P28)).
//!
//! With one focal length and zero skew, `A = [[f, 0, cx], [0, f, cy], [0, 0, 1]]`
//! and
//!
//! ```text
//! B ∝ A⁻ᵀ A⁻¹ = (1/f²) [[1, 0, −cx], [0, 1, −cy], [−cx, −cy, cx² + cy² + f²]]
//! ```
//!
//! so `b12 = 0`, `b11 = b22`, and the unknown is `b = (b11, b13, b23, b33)`.
//! For `H = [h1 h2 h3]` (columns; `h_ik` the k-th component of column i) the
//! constraints `h1ᵀBh2 = 0` (P19) and `h1ᵀBh1 = h2ᵀBh2` (P20) read
//! `w_12 · b = 0` and `(w_11 − w_22) · b = 0` with
//!
//! ```text
//! w_ij = [h_i1 h_j1 + h_i2 h_j2,  h_i1 h_j3 + h_i3 h_j1,  h_i2 h_j3 + h_i3 h_j2,  h_i3 h_j3]
//! ```
//!
//! Both rows of every image are stacked; `b` is the right singular vector of
//! the smallest singular value (the system is padded to square). Then
//!
//! ```text
//! cx = −b13/b11,   cy = −b23/b11,   f² = (b11 b33 − b13² − b23²)/b11²
//! ```
//!
//! (the paper's (P23)–(P25) are wrong). `f² ≤ 0` is refused with
//! [`CalibError::NonPositiveFocalSquared`].
//!
//! *Conditioning.* The constraints involve `h1`, `h2` only and are
//! homogeneous in each, so each image's two rows are divided by
//! `‖h1‖‖h2‖` (dimensionless rows; an affine, untilted image gives rows near
//! zero). The image coordinates are scaled by a nominal length `s` before
//! the solve (`H ← diag(1/s, 1/s, 1) H`, so `f → f/s`, `c → c/s`) and the
//! result is scaled back. A first pass uses `s` = [`NOMINAL_SCALE_MM`]; a
//! second pass uses `s = f` of the first, which balances `b` to about
//! `(1, −cx/f, −cy/f, 1)` for any focal length.
//!
//! *Extrinsics* (P26)–(P28): `λ = 1/‖A⁻¹h1‖`, `r1 = λA⁻¹h1`, `r2 = λA⁻¹h2`,
//! `r3 = r1 × r2`, `t = λA⁻¹h3`; the sign of `λ` is flipped if `t_z < 0`
//! (the template is in front of the sensor), and `[r1 r2 r3]` is replaced by
//! its nearest rotation `U diag(1, 1, det(UVᵀ)) Vᵀ`. The result is the pose
//! `sensor_from_template` (CONVENTIONS.md).

use nalgebra::{DMatrix, Matrix3, Vector3};
use psdcal_model::{Pose, SensorModel};

use crate::start::homography::{null_vector, Homography};
use crate::CalibError;

/// Image scale (mm) of the closed form's first pass.
pub const NOMINAL_SCALE_MM: f64 = 10.0;

/// Largest singular value of the row-normalised system below which every
/// image is affine and untilted: the template poses are parallel to the
/// sensor and the closed form has no information.
pub const PARALLEL_TOLERANCE: f64 = 1e-9;

/// Ratio of the second-smallest to the largest singular value below which the
/// closed form's null space is not unique.
pub const UNIQUENESS_TOLERANCE: f64 = 1e-9;

/// The closed-form solution and how it was obtained. It is returned even when
/// `f² ≤ 0`, so that a caller can report it; [`Self::focal_length`] and
/// [`Self::model`] refuse that case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosedFormSolution {
    /// Optical centre x, mm.
    pub cx: f64,
    /// Optical centre y, mm.
    pub cy: f64,
    /// `f²`, mm² (may be ≤ 0 on bad data).
    pub f_squared: f64,
    /// `b = (b11, b13, b23, b33)` in mm units (`b11 ∝ 1/f²`), unit norm,
    /// `b11 > 0`.
    pub b: [f64; 4],
    /// Singular values of the row-normalised, scaled system (final pass),
    /// descending.
    pub singular_values: [f64; 4],
    /// Image scale of the final pass, mm.
    pub scale: f64,
    /// Passes run (1 or 2).
    pub passes: usize,
    /// Number of homographies used.
    pub images: usize,
}

impl ClosedFormSolution {
    /// The focal length `√(f²)`, mm; [`CalibError::NonPositiveFocalSquared`]
    /// when `f² ≤ 0` or non-finite.
    pub fn focal_length(&self) -> Result<f64, CalibError> {
        if self.f_squared > 0.0 && self.f_squared.is_finite() {
            Ok(self.f_squared.sqrt())
        } else {
            Err(CalibError::NonPositiveFocalSquared {
                f_squared: self.f_squared,
            })
        }
    }

    /// The distortion-free pinhole `(f, cx, cy)`.
    pub fn model(&self) -> Result<SensorModel, CalibError> {
        Ok(SensorModel::pinhole(self.focal_length()?, self.cx, self.cy))
    }

    /// Second-smallest over largest singular value: how unique the solution
    /// is (compare with [`UNIQUENESS_TOLERANCE`]).
    pub fn uniqueness(&self) -> f64 {
        if self.singular_values[0] > 0.0 {
            self.singular_values[2] / self.singular_values[0]
        } else {
            0.0
        }
    }
}

/// `w_ij` of the module documentation, for columns `hi`, `hj`.
fn w(hi: &Vector3<f64>, hj: &Vector3<f64>) -> [f64; 4] {
    [
        hi[0] * hj[0] + hi[1] * hj[1],
        hi[0] * hj[2] + hi[2] * hj[0],
        hi[1] * hj[2] + hi[2] * hj[1],
        hi[2] * hj[2],
    ]
}

/// One pass at image scale `s`: `(b in scaled units, singular values)`.
fn solve_pass(homographies: &[Homography], s: f64) -> Result<([f64; 4], [f64; 4]), CalibError> {
    let mut a = DMatrix::zeros(2 * homographies.len(), 4);
    for (k, h) in homographies.iter().enumerate() {
        let scale = Vector3::new(1.0 / s, 1.0 / s, 1.0);
        let h1 = h.column(0).component_mul(&scale);
        let h2 = h.column(1).component_mul(&scale);
        let norm = h1.norm() * h2.norm();
        if !norm.is_finite() || norm <= 0.0 {
            return Err(CalibError::Numerical {
                stage: "closed form",
                reason: format!("homography {k} has a zero or non-finite column"),
            });
        }
        let w12 = w(&h1, &h2);
        let w11 = w(&h1, &h1);
        let w22 = w(&h2, &h2);
        for j in 0..4 {
            a[(2 * k, j)] = w12[j] / norm;
            a[(2 * k + 1, j)] = (w11[j] - w22[j]) / norm;
        }
    }
    let nv = null_vector(&a, "closed form")?;
    let sv = &nv.singular_values;
    let singular = [sv[0], sv[1], sv[2], sv[3]];
    let mut b = [nv.vector[0], nv.vector[1], nv.vector[2], nv.vector[3]];
    if b[0] < 0.0 {
        b = b.map(|v| -v);
    }
    Ok((b, singular))
}

/// Solves the closed form at scale `s` and converts to mm units.
fn pass(homographies: &[Homography], s: f64) -> Result<ClosedFormSolution, CalibError> {
    let (bs, singular_values) = solve_pass(homographies, s)?;
    if singular_values[0] <= PARALLEL_TOLERANCE {
        return Err(CalibError::Degenerate {
            reason: format!(
                "every homography is affine and untilted (closed-form system norm {:.2e}): the \
                 template poses are all parallel to the sensor, which leaves the focal length \
                 undetermined; tilt the template (10°–40°) in several directions",
                singular_values[0]
            ),
        });
    }
    if singular_values[2] <= UNIQUENESS_TOLERANCE * singular_values[0] {
        return Err(CalibError::Degenerate {
            reason: format!(
                "the closed-form system has no unique solution (second-smallest/largest singular \
                 value {:.2e}): the template planes are all parallel to each other; tilt the \
                 template in different directions",
                singular_values[2] / singular_values[0]
            ),
        });
    }
    if bs[0] <= 1e-12 {
        return Err(CalibError::Degenerate {
            reason: format!(
                "closed form gives b11 = {:.3e} ≈ 0 (infinite focal length): the images are \
                 nearly affine",
                bs[0]
            ),
        });
    }
    // Back to mm units: b11 = b11'/s², b13 = b13'/s, b23 = b23'/s, b33 = b33'.
    let cx = -bs[1] / bs[0] * s;
    let cy = -bs[2] / bs[0] * s;
    let f_squared = (bs[0] * bs[3] - bs[1] * bs[1] - bs[2] * bs[2]) / (bs[0] * bs[0]) * s * s;
    let bmm = [bs[0] / (s * s), bs[1] / s, bs[2] / s, bs[3]];
    let norm = bmm.iter().map(|v| v * v).sum::<f64>().sqrt();
    let b = bmm.map(|v| v / norm);
    if !(cx.is_finite() && cy.is_finite() && f_squared.is_finite() && norm.is_finite()) {
        return Err(CalibError::Numerical {
            stage: "closed form",
            reason: "non-finite intrinsics".into(),
        });
    }
    Ok(ClosedFormSolution {
        cx,
        cy,
        f_squared,
        b,
        singular_values,
        scale: s,
        passes: 1,
        images: homographies.len(),
    })
}

/// Closed-form intrinsics `(f², cx, cy)` from at least two homographies
/// (docs/model.md §4.4). Two passes (see the module documentation); the returned
/// solution may have `f² ≤ 0`, which [`ClosedFormSolution::focal_length`]
/// refuses.
///
/// Errors: [`CalibError::TooFewImages`] for fewer than 2 homographies,
/// [`CalibError::Degenerate`] when the system vanishes (all poses parallel to
/// the sensor), has no unique null vector (template planes all parallel) or
/// gives `b11 ≈ 0`; [`CalibError::Numerical`] for non-finite results.
pub fn closed_form(homographies: &[Homography]) -> Result<ClosedFormSolution, CalibError> {
    if homographies.len() < 2 {
        return Err(CalibError::TooFewImages {
            usable: homographies.len(),
            needed: 2,
        });
    }
    let first = pass(homographies, NOMINAL_SCALE_MM)?;
    if first.f_squared > 0.0 {
        let s = first.f_squared.sqrt();
        if let Ok(mut second) = pass(homographies, s) {
            if second.f_squared > 0.0 {
                second.passes = 2;
                return Ok(second);
            }
        }
    }
    Ok(first)
}

/// Closed-form intrinsics as a distortion-free [`SensorModel`]; refuses
/// `f² ≤ 0` with [`CalibError::NonPositiveFocalSquared`].
pub fn closed_form_intrinsics(homographies: &[Homography]) -> Result<SensorModel, CalibError> {
    closed_form(homographies)?.model()
}

/// The pose `sensor_from_template` of one homography for intrinsics
/// `(f, cx, cy)` (zero skew), by (P26)–(P28) and the nearest rotation.
pub fn pose_from_homography(h: &Homography, f: f64, cx: f64, cy: f64) -> Result<Pose, CalibError> {
    if !(f > 0.0 && f.is_finite() && cx.is_finite() && cy.is_finite()) {
        return Err(CalibError::InvalidInput {
            reason: format!(
                "pose from homography needs finite f > 0 (f = {f}, cx = {cx}, cy = {cy})"
            ),
        });
    }
    let a_inv = |v: Vector3<f64>| Vector3::new((v.x - cx * v.z) / f, (v.y - cy * v.z) / f, v.z);
    let (g1, g2, g3) = (a_inv(h.column(0)), a_inv(h.column(1)), a_inv(h.column(2)));
    let n1 = g1.norm();
    if !n1.is_finite() || n1 <= 0.0 {
        return Err(CalibError::Numerical {
            stage: "pose from homography",
            reason: "‖A⁻¹h1‖ is zero or non-finite".into(),
        });
    }
    let mut lambda = 1.0 / n1;
    if g3.z * lambda < 0.0 {
        lambda = -lambda;
    }
    let t = g3 * lambda;
    if t.z.is_nan() || t.z <= 0.0 {
        return Err(CalibError::Degenerate {
            reason: format!(
                "the template origin is at depth {:.3e} mm: not in front of the sensor",
                t.z
            ),
        });
    }
    let r1 = g1 * lambda;
    let r2 = g2 * lambda;
    let r3 = r1.cross(&r2);
    let q = Matrix3::from_columns(&[r1, r2, r3]);
    let svd =
        nalgebra::linalg::SVD::try_new(q, true, true, f64::EPSILON, 10_000).ok_or_else(|| {
            CalibError::Numerical {
                stage: "pose from homography",
                reason: "SVD of the rotation estimate did not converge".into(),
            }
        })?;
    let (u, v_t) = match (svd.u, svd.v_t) {
        (Some(u), Some(v_t)) => (u, v_t),
        _ => {
            return Err(CalibError::Numerical {
                stage: "pose from homography",
                reason: "SVD returned no singular vectors".into(),
            })
        }
    };
    let d = (u * v_t).determinant().signum();
    let rot = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * v_t;
    let pose = Pose::from_rotation(&rot, t);
    if pose.to_array().iter().all(|v| v.is_finite()) {
        Ok(pose)
    } else {
        Err(CalibError::Numerical {
            stage: "pose from homography",
            reason: "non-finite pose".into(),
        })
    }
}
