//! Emitter position from the rays of two or more sensors with known poses
//! (docs/model.md §5: "for several sensors with known poses, intersect rays (least
//! squares for ≥ 2 sensors)").
//!
//! World frame, millimetres. Sensor `i` has the pose `world_from_sensor_i`
//! (`P_w = R_i P_s + o_i`, `o_i` its optical centre in the world) and
//! measures the normalised ray `z_i = (a_i, b_i)` with covariance `C_i`.
//!
//! 1. Start: the point nearest to all rays (sum of squared perpendicular
//!    distances), `[Σ (I − u_i u_iᵀ)] P = Σ (I − u_i u_iᵀ) o_i` with
//!    `u_i = R_i (a_i, b_i, 1)/‖·‖`.
//! 2. Refinement, by psdcal's one least-squares solver
//!    ([`psdcal_solver::solve`], Levenberg–Marquardt; the global block is
//!    the point `P`, there are no pose blocks): minimise
//!    `Σ (h_i(P) − z_i)ᵀ W_i (h_i(P) − z_i)` where
//!    `h_i(P) = (x/z, y/z)` of `P_s = R_iᵀ (P − o_i)` is the ray through `P`
//!    as sensor `i` would measure it; `W_i = C_i⁻¹` when every `C_i` is
//!    positive definite (maximum likelihood for Gaussian ray noise: each
//!    perpendicular miss is weighted by its angular covariance and range),
//!    otherwise, or when [`LocateOptions::weight_rays`] is off, `W_i = I`
//!    (unweighted angular misses). Each miss is whitened, `r_i = L_i (h_i(P)
//!    − z_i)` with `L_iᵀ L_i = W_i` (`L_i = G_i⁻¹` for `C_i = G_i G_iᵀ`), so
//!    the solver's cost `Σ ‖r_i‖²` is the weighted one. A point at a depth
//!    below [`MIN_DEPTH_MM`] in front of a sensor is outside the problem's
//!    domain (the step is rejected).
//! 3. Covariance, to first order (the sandwich form, valid for any `W_i`):
//!
//! ```text
//! J_i = ∂h_i/∂P = [[1/z, 0, −x/z²], [0, 1/z, −y/z²]] R_iᵀ
//! H   = Σ J_iᵀ W_i J_i
//! ∂P/∂z_i = H⁻¹ J_iᵀ W_i
//! Σ_P = Σ (∂P/∂z_i) C_i (∂P/∂z_i)ᵀ          ( = H⁻¹ when W_i = C_i⁻¹ )
//! ```
//!
//! Failures: fewer than two rays, parallel rays (largest mutual angle below
//! 1e-9 rad or a singular normal matrix), a solution behind one of the
//! sensors (rays that diverge or meet behind). Nearly parallel rays are
//! answered with [`Caution::NearlyParallelRays`].

use nalgebra::{Matrix2, Matrix2x3, Matrix3, Matrix3x2, Vector2, Vector3};
use psdcal_model::Pose;
use psdcal_solver::{linearize, solve, Problem, ResidualTerm, SolverOptions, Step};

use crate::calibrated_sensor::LocateOptions;
use crate::caution::Caution;
use crate::error::{exceeds, LocateError};

/// Largest mutual angle below which rays are parallel, rad.
pub const PARALLEL_RAYS_RAD: f64 = 1e-9;
/// Smallest depth accepted in front of a sensor, mm.
pub const MIN_DEPTH_MM: f64 = 1e-9;
/// Iteration budget of the refinement (solver iterations, accepted or not).
pub const MAX_ITERATIONS: usize = 100;

/// One sensor's ray in the world.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldRay {
    /// Sensor identifier (for messages).
    pub sensor: String,
    /// The sensor's pose in the world.
    pub world_from_sensor: Pose,
    /// Measured normalised ray `(a, b)`, sensor frame.
    pub ray_ab: Vector2<f64>,
    /// Covariance of `(a, b)`.
    pub covariance_ab: Matrix2<f64>,
}

/// A triangulated position.
#[derive(Debug, Clone, PartialEq)]
pub struct Triangulation {
    /// The position, world frame, mm.
    pub position: Vector3<f64>,
    /// Its covariance, mm².
    pub covariance: Matrix3<f64>,
    /// `∂P/∂(a_i, b_i)` per ray (3×2), mm.
    pub wrt_rays: Vec<Matrix3x2<f64>>,
    /// Depth of the position in each sensor's frame, mm.
    pub depths_mm: Vec<f64>,
    /// Perpendicular distance from the position to each ray, mm.
    pub miss_mm: Vec<f64>,
    /// Largest angle between two rays, rad.
    pub max_ray_angle: f64,
    /// Whether the rays were weighted by their inverse covariances.
    pub weighted: bool,
    /// Iterations of the solver (accepted and rejected steps).
    pub iterations: usize,
    /// Reasons for care.
    pub cautions: Vec<Caution>,
}

impl Triangulation {
    /// `Σ (∂P/∂z_i) C_i (∂P/∂z_i)ᵀ` for other ray covariances `C_i` (e.g.
    /// only the calibrations' part), mm².
    pub fn covariance_from(&self, ray_covariances: &[Matrix2<f64>]) -> Matrix3<f64> {
        let c: Matrix3<f64> = self
            .wrt_rays
            .iter()
            .zip(ray_covariances)
            .map(|(j, c)| j * c * j.transpose())
            .sum();
        (c + c.transpose()) * 0.5
    }
}

struct Frame {
    r: Matrix3<f64>,
    origin: Vector3<f64>,
}

impl Frame {
    fn sensor_point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.r.transpose() * (p - self.origin)
    }

    /// `h(P)` and `∂h/∂P`.
    fn predict(&self, p: &Vector3<f64>) -> (Vector2<f64>, Matrix2x3<f64>) {
        let q = self.sensor_point(p);
        let iz = 1.0 / q.z;
        let dh = Matrix2x3::new(iz, 0.0, -q.x * iz * iz, 0.0, iz, -q.y * iz * iz);
        (Vector2::new(q.x * iz, q.y * iz), dh * self.r.transpose())
    }
}

/// Intersects two or more rays in the least-squares sense.
///
/// ```
/// use nalgebra::{Matrix2, Vector2, Vector3};
/// use psdcal_locate::{triangulate, LocateOptions, WorldRay};
/// use psdcal_model::Pose;
///
/// // Two sensors 1 m apart on the world x axis, both looking along +z,
/// // see an emitter at (200, 100, 3000) mm.
/// let emitter = Vector3::new(200.0, 100.0, 3000.0);
/// let rays: Vec<WorldRay> = [-500.0, 500.0]
///     .iter()
///     .map(|&x| {
///         let pose = Pose::new(Vector3::zeros(), Vector3::new(x, 0.0, 0.0));
///         let p = emitter - pose.t;
///         WorldRay {
///             sensor: format!("s{x}"),
///             world_from_sensor: pose,
///             ray_ab: Vector2::new(p.x / p.z, p.y / p.z),
///             covariance_ab: Matrix2::identity() * 1e-8,
///         }
///     })
///     .collect();
/// let t = triangulate(&rays, &LocateOptions::default()).unwrap();
/// assert!((t.position - emitter).norm() < 1e-9);
/// // Depth is the least certain direction.
/// assert!(t.covariance[(2, 2)] > t.covariance[(0, 0)]);
/// ```
pub fn triangulate(
    rays: &[WorldRay],
    options: &LocateOptions,
) -> Result<Triangulation, LocateError> {
    options.check()?;
    if rays.len() < 2 {
        return Err(LocateError::TooFewRays { found: rays.len() });
    }
    for ray in rays {
        let all = ray
            .ray_ab
            .iter()
            .chain(ray.covariance_ab.iter())
            .chain(ray.world_from_sensor.rvec.iter())
            .chain(ray.world_from_sensor.t.iter());
        if all.into_iter().any(|v| !v.is_finite()) {
            return Err(LocateError::NonFinite {
                what: "ray, covariance or sensor pose",
            });
        }
    }
    let frames: Vec<Frame> = rays
        .iter()
        .map(|ray| Frame {
            r: ray.world_from_sensor.rotation(),
            origin: ray.world_from_sensor.t,
        })
        .collect();
    let directions: Vec<Vector3<f64>> = rays
        .iter()
        .zip(&frames)
        .map(|(ray, f)| f.r * Vector3::new(ray.ray_ab.x, ray.ray_ab.y, 1.0).normalize())
        .collect();
    let max_ray_angle = max_mutual_angle(&directions);
    if !exceeds(max_ray_angle, PARALLEL_RAYS_RAD) {
        return Err(LocateError::ParallelRays {
            angle_deg: max_ray_angle.to_degrees(),
        });
    }
    let parallel = || LocateError::ParallelRays {
        angle_deg: max_ray_angle.to_degrees(),
    };
    // 1. Nearest point to all rays.
    let mut m = Matrix3::zeros();
    let mut rhs = Vector3::zeros();
    for (u, f) in directions.iter().zip(&frames) {
        let a = Matrix3::identity() - u * u.transpose();
        m += a;
        rhs += a * f.origin;
    }
    let mut p = m.try_inverse().ok_or_else(parallel)? * rhs;
    check_depths(rays, &frames, &p)?;
    // 2. Weighted refinement.
    let weighted =
        options.weight_rays && rays.iter().all(|r| is_positive_definite(&r.covariance_ab));
    let (weights, whitening): (Vec<Matrix2<f64>>, Vec<Matrix2<f64>>) = rays
        .iter()
        .map(|r| {
            let identity = (Matrix2::identity(), Matrix2::identity());
            if !weighted {
                return identity;
            }
            // C = G Gᵀ: W = C⁻¹ = G⁻ᵀ G⁻¹, whitening L = G⁻¹.
            let w = r.covariance_ab.try_inverse();
            let l = r.covariance_ab.cholesky().and_then(|c| c.l().try_inverse());
            match (w, l) {
                (Some(w), Some(l)) => (w, l),
                _ => identity,
            }
        })
        .unzip();
    let problem = RayIntersection {
        frames: &frames,
        rays,
        whitening: &whitening,
    };
    let solution = solve(&problem, p, &solver_options()).map_err(|_| parallel())?;
    let iterations = solution.report.iterations;
    if !solution.report.termination.converged() {
        return Err(LocateError::NotConverged { iterations });
    }
    p = solution.state;
    check_depths(rays, &frames, &p)?;
    // 3. Covariance: H = Σ J_iᵀ W_i J_i from the solver's normal equations.
    let h = linearize(&problem, &p, None).map_err(|_| parallel())?.u;
    let h_inv = Matrix3::from_iterator(h.iter().copied())
        .try_inverse()
        .ok_or_else(parallel)?;
    let wrt_rays: Vec<Matrix3x2<f64>> = frames
        .iter()
        .zip(&weights)
        .map(|(f, w)| h_inv * f.predict(&p).1.transpose() * w)
        .collect();
    let mut cautions = Vec::new();
    if max_ray_angle < options.ray_angle_warning_rad {
        cautions.push(Caution::NearlyParallelRays {
            angle_deg: max_ray_angle.to_degrees(),
        });
    }
    let mut t = Triangulation {
        position: p,
        covariance: Matrix3::zeros(),
        depths_mm: frames.iter().map(|f| f.sensor_point(&p).z).collect(),
        miss_mm: directions
            .iter()
            .zip(&frames)
            .map(|(u, f)| {
                let v = p - f.origin;
                (v - u * u.dot(&v)).norm()
            })
            .collect(),
        wrt_rays,
        max_ray_angle,
        weighted,
        iterations,
        cautions,
    };
    let covs: Vec<Matrix2<f64>> = rays.iter().map(|r| r.covariance_ab).collect();
    t.covariance = t.covariance_from(&covs);
    if !(t
        .position
        .iter()
        .chain(t.covariance.iter())
        .all(|v| v.is_finite()))
    {
        return Err(parallel());
    }
    Ok(t)
}

/// Solver options of the refinement: the iteration budget, tolerances tight
/// enough that the solver stops on a negligible step or when no lower cost
/// exists to machine precision, and a negligible starting damping. The
/// problem is nearly linear near the nearest point, so the first step is
/// (almost) Gauss–Newton's and lands on the minimum to rounding; a damped
/// first step would leave the rest of the way to steps whose cost decrease
/// is below the cost's rounding (residuals of 1e-8 rad are rounded at
/// 1e-16), which are rejected.
fn solver_options() -> SolverOptions {
    SolverOptions {
        max_iterations: MAX_ITERATIONS,
        cost_tolerance: 0.0,
        step_tolerance: 1e-12,
        initial_lambda: 1e-12,
        ..SolverOptions::default()
    }
}

/// The refinement as a problem for the solver: the global block is the
/// point `P` (3 parameters), one two-row residual per ray (its whitened
/// angular miss), no pose blocks.
struct RayIntersection<'a> {
    frames: &'a [Frame],
    rays: &'a [WorldRay],
    whitening: &'a [Matrix2<f64>],
}

/// A point at which some sensor sees nothing (behind it or at its centre).
struct OutOfDomain;

impl Problem for RayIntersection<'_> {
    type State = Vector3<f64>;
    type Error = OutOfDomain;

    fn global_len(&self) -> usize {
        3
    }

    fn block_count(&self) -> usize {
        0
    }

    fn evaluate(
        &self,
        p: &Vector3<f64>,
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>),
    ) -> Result<(), OutOfDomain> {
        for ((f, ray), l) in self.frames.iter().zip(self.rays).zip(self.whitening) {
            if !exceeds(f.sensor_point(p).z, MIN_DEPTH_MM) {
                return Err(OutOfDomain);
            }
            let (pred, j) = f.predict(p);
            let r = l * (pred - ray.ray_ab);
            let a = if jacobians { l * j } else { Matrix2x3::zeros() };
            // Both column-major: `a[2·k + row]` is ∂r_row/∂P_k.
            visit(&ResidualTerm {
                r: r.as_slice(),
                a: a.as_slice(),
                block: None,
            });
        }
        Ok(())
    }

    fn apply_step(&self, p: &Vector3<f64>, step: &Step) -> Option<Vector3<f64>> {
        let next = p + Vector3::new(step.da[0], step.da[1], step.da[2]);
        next.iter().all(|v| v.is_finite()).then_some(next)
    }
}

fn check_depths(rays: &[WorldRay], frames: &[Frame], p: &Vector3<f64>) -> Result<(), LocateError> {
    for (ray, f) in rays.iter().zip(frames) {
        let depth = f.sensor_point(p).z;
        if !exceeds(depth, MIN_DEPTH_MM) {
            return Err(LocateError::BehindSensor {
                sensor: ray.sensor.clone(),
                depth_mm: depth,
            });
        }
    }
    Ok(())
}

/// Largest angle between two of the unit vectors, rad.
pub fn max_mutual_angle(directions: &[Vector3<f64>]) -> f64 {
    let mut max = 0.0f64;
    for (i, u) in directions.iter().enumerate() {
        for v in &directions[i + 1..] {
            max = max.max(u.cross(v).norm().atan2(u.dot(v)));
        }
    }
    max
}

/// Whether a 2×2 covariance is positive definite with a condition number
/// below 1e12.
fn is_positive_definite(c: &Matrix2<f64>) -> bool {
    let (a, b, d) = (c[(0, 0)], 0.5 * (c[(0, 1)] + c[(1, 0)]), c[(1, 1)]);
    let mean = 0.5 * (a + d);
    let radius = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (lo, hi) = (mean - radius, mean + radius);
    hi > 0.0 && lo > 1e-12 * hi
}
