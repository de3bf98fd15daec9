//! Angle of arrival of a measured impact point (docs/model.md §5, the paper's
//! (P39)), with its Jacobians, through the model's chain of stages
//! (psdcal-model's `Model`; a calibration's standard chain is
//! `Model::standard` of its parameters).
//!
//! Sensor frame (CONVENTIONS.md): origin at the PSD's electrical centre, `z`
//! along the optical axis towards the scene; millimetres, radians.
//!
//! A measured point `m = (xd, yd)` is corrected to the ideal pinhole point
//! `p = (x, y)` (docs/model.md §2), which has the normalised ray `(a, b, 1)`:
//!
//! ```text
//! b = (y − cy) / f,     a = (x − cx − γ b) / f
//! αx = atan(a),         αy = atan(b)                      (P39)
//! d  = (a, b, 1) / √(1 + a² + b²)                           unit ray, sensor frame
//! ```
//!
//! Without skew, `αx = atan((x − cx)/f)` exactly as (P39) (the paper writes
//! `x` for the offset from the optical centre). The Jacobians follow the
//! chain `m → p → (a, b) → α`:
//!
//! ```text
//! ∂(a,b)/∂m = N_p U_m                 U = ∂p/∂m, N_p = ∂(a,b)/∂p
//! ∂(a,b)/∂θ = N_p U_θ + N_θ           (θ: the 11 model parameters, Param::ALL order)
//! ∂α/∂(a,b) = diag(1/(1 + a²), 1/(1 + b²))
//! ```
//!
//! Here, a point is answered where the correction is finite and locally
//! invertible without folding over (`det U_m > 0`, the criterion of the
//! model's inverse distortion); elsewhere there is no angle of arrival, only
//! [`LocateError::OutsideValidRegion`]. A point past a fold can have
//! `det U_m > 0` again (with a mirrored ideal point): the calibrated
//! sensor ([`crate::CalibratedSensor::aoa`]) also checks its valid region
//! (docs/model.md §8.2, [`psdcal_model::ValidRegion`]), the part of the
//! active area the optical centre reaches without crossing a fold.

use nalgebra::{Matrix2, SMatrix, Unit, Vector2, Vector3};
use psdcal_model::{Model, Param, N_PARAMS};

use crate::error::{exceeds, finite, LocateError};

/// Smallest determinant of `∂ideal/∂measured` accepted (the threshold of the
/// model's inverse distortion).
pub const MIN_CORRECTION_DET: f64 = 1e-12;

/// The angle of arrival of one measured point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngleOfArrival {
    /// Measured impact point, mm, sensor frame.
    pub measured: Vector2<f64>,
    /// Ideal (corrected) point, mm, sensor frame.
    pub ideal: Vector2<f64>,
    /// Normalised ray `(a, b)`: the ray is `(a, b, 1)` in the sensor frame.
    pub ray_ab: Vector2<f64>,
    /// Angles of arrival `(αx, αy) = (atan a, atan b)`, rad.
    pub alpha: Vector2<f64>,
    /// Unit ray towards the emitter, sensor frame.
    pub direction: Unit<Vector3<f64>>,
}

/// Jacobians of an angle of arrival.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AoaJacobians {
    /// `∂(a, b)/∂θ`, 2×11 in [`psdcal_model::Param::ALL`] order.
    pub ray_wrt_model: SMatrix<f64, 2, N_PARAMS>,
    /// `∂(a, b)/∂m`, 2×2, with respect to the measured point.
    pub ray_wrt_measured: Matrix2<f64>,
    /// `∂(αx, αy)/∂(a, b)`, diagonal.
    pub alpha_wrt_ray: Matrix2<f64>,
}

impl AoaJacobians {
    /// `∂α/∂θ` (2×11).
    pub fn alpha_wrt_model(&self) -> SMatrix<f64, 2, N_PARAMS> {
        self.alpha_wrt_ray * self.ray_wrt_model
    }

    /// `∂α/∂m` (2×2).
    pub fn alpha_wrt_measured(&self) -> Matrix2<f64> {
        self.alpha_wrt_ray * self.ray_wrt_measured
    }
}

/// `(αx, αy)` of a normalised ray `(a, b)`, rad.
pub fn alpha_from_ray(ray_ab: &Vector2<f64>) -> Vector2<f64> {
    Vector2::new(ray_ab.x.atan(), ray_ab.y.atan())
}

/// `∂(αx, αy)/∂(a, b)` = `diag(1/(1 + a²), 1/(1 + b²))`.
pub fn alpha_wrt_ray(ray_ab: &Vector2<f64>) -> Matrix2<f64> {
    Matrix2::new(
        1.0 / (1.0 + ray_ab.x * ray_ab.x),
        0.0,
        0.0,
        1.0 / (1.0 + ray_ab.y * ray_ab.y),
    )
}

/// The angle of arrival of a measured point.
///
/// ```
/// use nalgebra::Vector2;
/// use psdcal_locate::angle_of_arrival;
/// use psdcal_model::{Model, SensorModel};
///
/// // A distortion-free 8 mm lens centred on the PSD: αx = atan(x / f).
/// let model = Model::standard(&SensorModel::pinhole(8.0, 0.0, 0.0));
/// let aoa = angle_of_arrival(&model, &Vector2::new(2.0, 0.0)).unwrap();
/// assert!((aoa.alpha.x - (2.0f64 / 8.0).atan()).abs() < 1e-15);
/// assert_eq!(aoa.alpha.y, 0.0);
/// ```
pub fn angle_of_arrival(
    model: &Model,
    measured: &Vector2<f64>,
) -> Result<AngleOfArrival, LocateError> {
    angle_of_arrival_with_jacobians(model, measured).map(|(aoa, _)| aoa)
}

/// The angle of arrival of a measured point and its Jacobians with respect
/// to the model parameters and the measured point.
pub fn angle_of_arrival_with_jacobians(
    model: &Model,
    measured: &Vector2<f64>,
) -> Result<(AngleOfArrival, AoaJacobians), LocateError> {
    finite(measured.x, "measured x")?;
    finite(measured.y, "measured y")?;
    model.validate()?;
    let outside = |reason| LocateError::OutsideValidRegion {
        x: measured.x,
        y: measured.y,
        reason,
    };
    let mut jac = model.jacobian_buffer();
    let ideal = model.ideal_with_jacobians(measured, &mut jac);
    if !(ideal.iter().all(|v| v.is_finite())
        && jac.wrt_point.iter().all(|v| v.is_finite())
        && jac.wrt_params.iter().all(|v| v.is_finite()))
    {
        return Err(outside("the distortion correction overflows"));
    }
    if !exceeds(jac.wrt_point.determinant(), MIN_CORRECTION_DET) {
        return Err(outside(
            "the distortion correction folds over there (its Jacobian is singular or reverses \
             orientation)",
        ));
    }
    let ray_ab = model.ray_of_ideal_with_jacobians(&ideal, &mut jac);
    let ray_wrt_measured = jac.wrt_point;
    let mut ray_wrt_model = SMatrix::<f64, 2, N_PARAMS>::zeros();
    for p in Param::ALL {
        if let Some(c) = model.index(p.name()) {
            ray_wrt_model.set_column(p.index(), &jac.column(c));
        }
    }
    if !(ray_ab.iter().all(|v| v.is_finite()) && ray_wrt_model.iter().all(|v| v.is_finite())) {
        return Err(outside("the ray overflows"));
    }
    let direction = Unit::new_normalize(Vector3::new(ray_ab.x, ray_ab.y, 1.0));
    Ok((
        AngleOfArrival {
            measured: *measured,
            ideal,
            ray_ab,
            alpha: alpha_from_ray(&ray_ab),
            direction,
        },
        AoaJacobians {
            ray_wrt_model,
            ray_wrt_measured,
            alpha_wrt_ray: alpha_wrt_ray(&ray_ab),
        },
    ))
}

/// The measured point whose ray is `(a, b, 1)` (the inverse of
/// [`angle_of_arrival`]): the pinhole point `x = f a + γ b + cx`,
/// `y = f b + cy`, distorted by Newton's method (docs/model.md §2) and polished
/// by one more Newton step (`Model::measured_from_ideal`).
///
/// ```
/// use nalgebra::Vector2;
/// use psdcal_locate::{angle_of_arrival, measured_from_ray};
/// use psdcal_model::{Model, SensorModel};
///
/// let model = Model::standard(&SensorModel::paper_lens2());
/// let m = measured_from_ray(&model, &Vector2::new(0.2, -0.1)).unwrap();
/// let aoa = angle_of_arrival(&model, &m).unwrap();
/// assert!((aoa.ray_ab - Vector2::new(0.2, -0.1)).norm() < 1e-12);
/// ```
pub fn measured_from_ray(
    model: &Model,
    ray_ab: &Vector2<f64>,
) -> Result<Vector2<f64>, LocateError> {
    finite(ray_ab.x, "ray a")?;
    finite(ray_ab.y, "ray b")?;
    model.validate()?;
    // Polished by one more Newton step: Newton stops at 1e-12 mm, which a
    // 5 m lever arm turns into 1e-9 mm; the polished point is exact to
    // rounding.
    Ok(model.measured_from_ideal(&model.ideal_of_ray(ray_ab))?)
}

/// The normalised ray `(a, b)` of a sensor-frame direction or point in front
/// of the sensor (`z > 0`).
pub fn ray_of_point(p_sensor: &Vector3<f64>) -> Result<Vector2<f64>, LocateError> {
    if !p_sensor.iter().all(|v| v.is_finite()) {
        return Err(LocateError::NonFinite {
            what: "sensor-frame point",
        });
    }
    if !exceeds(p_sensor.z, 0.0) {
        return Err(LocateError::InvalidInput {
            what: "sensor-frame point",
            reason: format!(
                "it is not in front of the sensor (z = {} mm); expected z > 0",
                p_sensor.z
            ),
        });
    }
    Ok(Vector2::new(
        p_sensor.x / p_sensor.z,
        p_sensor.y / p_sensor.z,
    ))
}
