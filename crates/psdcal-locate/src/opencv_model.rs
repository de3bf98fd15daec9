//! OpenCV's rational camera model (`CALIB_RATIONAL_MODEL`, mrcal's
//! `LENSMODEL_OPENCV8`) in the sensor's millimetres, the target of
//! `psdcal export` (docs/model.md §8.7).
//!
//! OpenCV writes its model in the direction **ray → image** (psdcal's is
//! measured → ideal → ray). For the normalised ray `(x', y')` (psdcal's
//! `(a, b)`), with `r² = x'² + y'²`:
//!
//! ```text
//! q  = (1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ + k6 r⁶)
//! x″ = x' q + 2 p1 x'y' + p2 (r² + 2x'²)
//! y″ = y' q + p1 (r² + 2y'²) + 2 p2 x'y'
//! u  = fx x″ + cx,    v = fy y″ + cy
//! ```
//!
//! Here `fx, fy, cx, cy` are in mm on the sensor; a pixel pitch turns them
//! into pixels (`psdcal export`: `u_px = 1000 (u + Lx/2)/pitch − 0.5`). The
//! coefficients are dimensionless and the same in both. The parameter
//! vector is mrcal's order `fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6`
//! (OpenCV's distortion vector is its last eight). The 5-coefficient model
//! (ROS's `plumb_bob`) is this one with `k4 = k5 = k6 = 0`.
//!
//! [`OpenCv8::project_with_jacobians`] gives `∂(u, v)/∂θ` (2×12) and
//! `∂(u, v)/∂(x', y')`; [`OpenCv8::unproject`] inverts the projection by
//! Newton's method on the latter (the ray of an image point).

use nalgebra::{Matrix2, SMatrix, Vector2};

/// Number of parameters.
pub const OPENCV8_LEN: usize = 12;

/// Parameter names in vector order (mrcal's).
pub const OPENCV8_NAMES: [&str; OPENCV8_LEN] = [
    "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6",
];

/// Indices of the coefficients that the 5-coefficient model holds at zero.
pub const RATIONAL_ONLY: [usize; 3] = [9, 10, 11];

/// OpenCV's rational model with its camera matrix in mm on the sensor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenCv8 {
    /// `fx, fy, cx, cy` (mm), `k1, k2, p1, p2, k3, k4, k5, k6`.
    pub params: [f64; OPENCV8_LEN],
}

/// A projection with its Jacobians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projected {
    /// `(u, v)`, mm.
    pub point: Vector2<f64>,
    /// `∂(u, v)/∂θ`, 2×12.
    pub wrt_params: SMatrix<f64, 2, OPENCV8_LEN>,
    /// `∂(u, v)/∂(x', y')`.
    pub wrt_ray: Matrix2<f64>,
}

impl OpenCv8 {
    /// The pinhole `f, (cx, cy)` with no distortion.
    pub fn pinhole(f: f64, cx: f64, cy: f64) -> Self {
        let mut params = [0.0; OPENCV8_LEN];
        params[..4].copy_from_slice(&[f, f, cx, cy]);
        Self { params }
    }

    /// The image point of the ray `(x', y', 1)`, mm.
    pub fn project(&self, ray: &Vector2<f64>) -> Vector2<f64> {
        self.project_with_jacobians(ray).point
    }

    /// The image point with `∂/∂θ` and `∂/∂ray`.
    pub fn project_with_jacobians(&self, ray: &Vector2<f64>) -> Projected {
        let [fx, fy, _, _, k1, k2, p1, p2, k3, k4, k5, k6] = self.params;
        let (x, y) = (ray.x, ray.y);
        let r2 = x * x + y * y;
        let (r4, r6) = (r2 * r2, r2 * r2 * r2);
        let num = 1.0 + k1 * r2 + k2 * r4 + k3 * r6;
        let den = 1.0 + k4 * r2 + k5 * r4 + k6 * r6;
        let q = num / den;
        let xd = x * q + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
        let yd = y * q + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
        let point = Vector2::new(fx * xd + self.params[2], fy * yd + self.params[3]);
        // ∂q/∂r² and the coefficients' columns.
        let dnum = k1 + 2.0 * k2 * r2 + 3.0 * k3 * r4;
        let dden = k4 + 2.0 * k5 * r2 + 3.0 * k6 * r4;
        let dq = (dnum * den - num * dden) / (den * den);
        let mut w = SMatrix::<f64, 2, OPENCV8_LEN>::zeros();
        w[(0, 0)] = xd;
        w[(1, 1)] = yd;
        w[(0, 2)] = 1.0;
        w[(1, 3)] = 1.0;
        // (column, ∂q/∂coefficient)
        let radial = [
            (4, r2 / den),
            (5, r4 / den),
            (8, r6 / den),
            (9, -q * r2 / den),
            (10, -q * r4 / den),
            (11, -q * r6 / den),
        ];
        for (c, dqc) in radial {
            w[(0, c)] = fx * x * dqc;
            w[(1, c)] = fy * y * dqc;
        }
        w[(0, 6)] = fx * 2.0 * x * y;
        w[(1, 6)] = fy * (r2 + 2.0 * y * y);
        w[(0, 7)] = fx * (r2 + 2.0 * x * x);
        w[(1, 7)] = fy * 2.0 * x * y;
        let dxx = q + 2.0 * x * x * dq + 2.0 * p1 * y + 6.0 * p2 * x;
        let dxy = 2.0 * x * y * dq + 2.0 * p1 * x + 2.0 * p2 * y;
        let dyx = 2.0 * x * y * dq + 2.0 * p1 * x + 2.0 * p2 * y;
        let dyy = q + 2.0 * y * y * dq + 6.0 * p1 * y + 2.0 * p2 * x;
        let wrt_ray = Matrix2::new(fx * dxx, fx * dxy, fy * dyx, fy * dyy);
        Projected {
            point,
            wrt_params: w,
            wrt_ray,
        }
    }

    /// The ray `(x', y')` of the image point `image` (mm), by Newton's
    /// method from `start` to 1e-13 mm; `None` when it does not converge or
    /// the projection folds (`det ∂(u, v)/∂ray ≤ 0`) on the way.
    pub fn unproject(&self, image: &Vector2<f64>, start: &Vector2<f64>) -> Option<Vector2<f64>> {
        let mut ray = *start;
        for _ in 0..100 {
            let p = self.project_with_jacobians(&ray);
            let e = p.point - image;
            if e.norm() < 1e-13 {
                return Some(ray);
            }
            if p.wrt_ray.determinant() <= 0.0 {
                return None;
            }
            let step = p.wrt_ray.try_inverse()? * e;
            ray -= step;
            if !(ray.x.is_finite() && ray.y.is_finite()) {
                return None;
            }
        }
        let e = self.project(&ray) - image;
        (e.norm() < 1e-11).then_some(ray)
    }
}
