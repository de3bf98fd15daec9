//! Distortion: measured (distorted) impact point → ideal pinhole point, and
//! back (docs/model.md §2, the paper's (P7)–(P16)).
//!
//! The maps are the [`Model`](crate::Model)'s stages ([`crate::stages`]);
//! for a measured point `(xd, yd)`, the standard chain applies, in this
//! order:
//!
//! ```text
//! 1. PSD radial about (0, 0):   h² = xd² + yd²,  (xu, yu) = (xd, yd)(1 + l1 h² + l2 h⁴)
//! 2. lens radial about (cx, cy): dx = xu − cx, dy = yu − cy, r² = dx² + dy²,
//!                                ρ = k1 r² + k2 r⁴ + k3 r⁶
//! 3. lens tangential:            tx = p1 (r² + 2dx²) + 2 p2 dx dy
//!                                ty = p2 (r² + 2dy²) + 2 p1 dx dy
//! 4. x = xu + dx ρ + tx,         y = yu + dy ρ + ty
//! ```
//!
//! This module holds the inverse (ideal → measured), which has no closed
//! form: it is solved per point by Newton's method on the 2×2 Jacobian, with
//! step halving, to 1e-12 mm, and fails with a typed error when it does not
//! converge or when the Jacobian is singular or folds over (`det ≤ 0`):
//! outside the model's valid region there is no silent wrong point
//! ([`crate::Model::measured_from_ideal`] and
//! [`crate::Model::measured_from_ideal_to_tolerance`]).

use nalgebra::{Matrix2, Vector2};

use crate::ModelError;

/// Target accuracy of the inverse distortion, mm.
pub const INVERSE_TOLERANCE_MM: f64 = 1e-12;
/// Newton iteration budget of the inverse distortion.
pub const INVERSE_MAX_ITERATIONS: usize = 60;

/// The point `m` with `map(m) = target` for a measured → ideal map with 2×2
/// Jacobian `jacobian`: Newton's method with step halving (which keeps the
/// iteration on the branch it started on), to [`INVERSE_TOLERANCE_MM`];
/// a typed error when the Jacobian is singular or folds over (`det ≤ 0`) or
/// the iteration does not converge. With `polish`, one more Newton step is
/// taken from the converged point when it lowers the residual (the inverse is
/// then exact to rounding, so that derivatives through it match finite
/// differences even for distortions below the tolerance).
pub fn invert_newton(
    target: &Vector2<f64>,
    map: &dyn Fn(&Vector2<f64>) -> Vector2<f64>,
    jacobian: &dyn Fn(&Vector2<f64>) -> Matrix2<f64>,
    polish: bool,
) -> Result<Vector2<f64>, ModelError> {
    invert_newton_from(target, target, map, jacobian, polish)
}

/// [`invert_newton`] started from `start` instead of from `target` (a
/// point known to be near the solution, such as the measured point whose
/// model prediction is sought: Newton then needs one or two steps).
pub fn invert_newton_from(
    target: &Vector2<f64>,
    start: &Vector2<f64>,
    map: &dyn Fn(&Vector2<f64>) -> Vector2<f64>,
    jacobian: &dyn Fn(&Vector2<f64>) -> Matrix2<f64>,
    polish: bool,
) -> Result<Vector2<f64>, ModelError> {
    let valid = |m: Vector2<f64>| -> Result<Vector2<f64>, ModelError> {
        let det = jacobian(&m).determinant();
        if det > 1e-12 {
            Ok(m)
        } else {
            Err(ModelError::SingularDistortion {
                x: m.x,
                y: m.y,
                det,
            })
        }
    };
    let finish = |m: Vector2<f64>, residual: Vector2<f64>| {
        if !polish || residual == Vector2::zeros() {
            return valid(m);
        }
        let polished = jacobian(&m)
            .try_inverse()
            .map(|inv| m - inv * residual)
            .filter(|c| (map(c) - target).norm() < residual.norm())
            .unwrap_or(m);
        valid(polished)
    };
    let mut m = if start.x.is_finite() && start.y.is_finite() {
        *start
    } else {
        *target
    };
    let mut residual = map(&m) - target;
    let mut last_step = f64::INFINITY;
    for iteration in 0..INVERSE_MAX_ITERATIONS {
        if residual.norm() <= INVERSE_TOLERANCE_MM {
            return finish(m, residual);
        }
        let jac = jacobian(&m);
        let det = jac.determinant();
        if det.is_nan() || det <= 1e-12 {
            return Err(ModelError::SingularDistortion {
                x: m.x,
                y: m.y,
                det,
            });
        }
        let step =
            Matrix2::new(jac[(1, 1)], -jac[(0, 1)], -jac[(1, 0)], jac[(0, 0)]) * residual / det;
        let mut alpha = 1.0;
        loop {
            let candidate = m - step * alpha;
            let r = map(&candidate) - target;
            if r.norm() < residual.norm() || alpha < 1e-6 {
                m = candidate;
                residual = r;
                last_step = step.norm() * alpha;
                break;
            }
            alpha *= 0.5;
        }
        if !(m.x.is_finite() && m.y.is_finite()) {
            return Err(ModelError::DistortionNotConverged {
                x: target.x,
                y: target.y,
                iterations: iteration + 1,
                last_step,
            });
        }
    }
    if residual.norm() <= INVERSE_TOLERANCE_MM {
        return finish(m, residual);
    }
    Err(ModelError::DistortionNotConverged {
        x: target.x,
        y: target.y,
        iterations: INVERSE_MAX_ITERATIONS,
        last_step,
    })
}
