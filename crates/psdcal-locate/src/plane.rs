//! Emitter position on a known plane (docs/model.md §5, the paper's Section 3.4
//! and Figure 9): the ray of an angle of arrival intersected with a plane
//! given in the sensor frame.
//!
//! Sensor frame, millimetres. The plane is `n·P = d` with `‖n‖ = 1` and
//! `d > 0` (the sensor's optical centre is not on it). The ray through the
//! normalised point `(a, b)` is `P(s) = s r`, `r = (a, b, 1)`, so
//!
//! ```text
//! q = n·r,   s = d / q,   P = s r                      (s > 0: in front of the sensor)
//! ∂P/∂r = s (I − r nᵀ / q)                              (columns a, b used)
//! ```
//!
//! A plane parallel to the sensor at distance `S` (`n = (0, 0, 1)`, `d = S`)
//! gives the paper's `X = S tan αx`, `Y = S tan αy`, `Z = S`. The angle
//! between the ray and the plane is `asin(|n·r̂|)`; a ray with
//! `|n·r̂| ≤ 1e-12` is parallel to the plane, and `s ≤ 0` means the ray
//! points away from it.

use nalgebra::{Matrix3, Matrix3x2, Unit, Vector2, Vector3};

use crate::error::{exceeds, finite, LocateError};

/// `|n·r̂|` at or below which a ray is taken as parallel to the plane.
pub const PARALLEL_COSINE: f64 = 1e-12;

/// A plane `n·P = d` in the sensor frame (mm), `‖n‖ = 1`, `d > 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    normal: Unit<Vector3<f64>>,
    offset_mm: f64,
}

impl Plane {
    /// The plane `normal·P = offset_mm` (sensor frame); the normal need not
    /// be a unit vector. It must not pass through the sensor's optical
    /// centre (`offset_mm ≠ 0`).
    ///
    /// ```
    /// use nalgebra::Vector3;
    /// use psdcal_locate::Plane;
    ///
    /// // The floor 2.5 m below a sensor looking along its own y axis: y = -2500 mm.
    /// let floor = Plane::new(Vector3::new(0.0, -1.0, 0.0), 2500.0).unwrap();
    /// assert_eq!(floor.offset_mm(), 2500.0);
    /// assert!(Plane::new(Vector3::zeros(), 1.0).is_err());
    /// ```
    pub fn new(normal: Vector3<f64>, offset_mm: f64) -> Result<Self, LocateError> {
        for v in normal.iter() {
            finite(*v, "plane normal")?;
        }
        finite(offset_mm, "plane offset")?;
        let norm = normal.norm();
        if !(norm > 0.0 && norm.is_finite()) {
            return Err(LocateError::InvalidInput {
                what: "plane",
                reason: "the normal is zero; expected a non-zero vector".into(),
            });
        }
        let d = offset_mm / norm;
        if !exceeds(d.abs(), 0.0) {
            return Err(LocateError::InvalidInput {
                what: "plane",
                reason: "it passes through the sensor's optical centre (offset 0); expected a \
                         plane at a distance from the sensor"
                    .into(),
            });
        }
        let sign = d.signum();
        Ok(Self {
            normal: Unit::new_unchecked(normal / norm * sign),
            offset_mm: d * sign,
        })
    }

    /// The plane parallel to the sensor at distance `distance_mm` in front of
    /// it (`Z = S`).
    pub fn parallel(distance_mm: f64) -> Result<Self, LocateError> {
        finite(distance_mm, "distance")?;
        if !exceeds(distance_mm, 0.0) {
            return Err(LocateError::InvalidInput {
                what: "distance",
                reason: format!("{distance_mm} mm; expected a positive distance"),
            });
        }
        Self::new(Vector3::z(), distance_mm)
    }

    /// Unit normal, sensor frame, oriented so that the offset is positive.
    pub fn normal(&self) -> &Unit<Vector3<f64>> {
        &self.normal
    }

    /// Distance of the plane from the sensor's optical centre, mm (> 0).
    pub fn offset_mm(&self) -> f64 {
        self.offset_mm
    }
}

/// Where a ray meets a plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneIntersection {
    /// The point, sensor frame, mm.
    pub position: Vector3<f64>,
    /// `∂P/∂(a, b)` (3×2), mm.
    pub wrt_ray: Matrix3x2<f64>,
    /// Distance from the optical centre to the point, mm.
    pub range_mm: f64,
    /// Angle between the ray and the plane, rad (π/2 = head-on).
    pub grazing_angle: f64,
}

/// Intersects the ray `(a, b, 1)` with `plane`.
///
/// ```
/// use nalgebra::Vector2;
/// use psdcal_locate::{intersect_plane, Plane};
///
/// // At S = 5 m, X = S tan αx = S a.
/// let hit = intersect_plane(&Plane::parallel(5000.0).unwrap(), &Vector2::new(0.1, -0.05)).unwrap();
/// assert!((hit.position.x - 500.0).abs() < 1e-9);
/// assert!((hit.position.y + 250.0).abs() < 1e-9);
/// assert_eq!(hit.position.z, 5000.0);
/// ```
pub fn intersect_plane(
    plane: &Plane,
    ray_ab: &Vector2<f64>,
) -> Result<PlaneIntersection, LocateError> {
    finite(ray_ab.x, "ray a")?;
    finite(ray_ab.y, "ray b")?;
    let r = Vector3::new(ray_ab.x, ray_ab.y, 1.0);
    let n = plane.normal.into_inner();
    let q = n.dot(&r);
    let cos = q.abs() / r.norm();
    if !exceeds(cos, PARALLEL_COSINE) {
        return Err(LocateError::ParallelToPlane { cos });
    }
    let s = plane.offset_mm / q;
    if !exceeds(s, 0.0) || !s.is_finite() {
        return Err(LocateError::PointsAwayFromPlane {
            distance_mm: s * r.norm(),
        });
    }
    let position = r * s;
    let full: Matrix3<f64> = (Matrix3::identity() - r * n.transpose() / q) * s;
    let wrt_ray = full.fixed_view::<3, 2>(0, 0).into_owned();
    if !(position.iter().all(|v| v.is_finite()) && wrt_ray.iter().all(|v| v.is_finite())) {
        return Err(LocateError::ParallelToPlane { cos });
    }
    Ok(PlaneIntersection {
        position,
        wrt_ray,
        range_mm: s * r.norm(),
        grazing_angle: cos.min(1.0).asin(),
    })
}
