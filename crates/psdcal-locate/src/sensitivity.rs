//! Sensitivity of the angle of arrival to the model's parameters: the
//! paper's small-angle form (P40)–(P42) and the full-model error that the
//! error maps use (Section 3.4, Figure 9).
//!
//! The paper differentiates (P39) `αx = atan(x/f)`, `x` the ideal point's
//! offset from the optical centre (mm):
//!
//! ```text
//! ∂αx/∂x = f / (f² + x²)                                      (P40)
//! ∂αx/∂f = −x / (f² + x²)                                     (P41, the paper writes |x/(f²+x²)|)
//! ε_α    = |f/(f² + x²)| Δx + |x/(f² + x²)| Δf                 (P42)
//! ```
//!
//! and likewise for `y`. That is a first-order bound for one axis, with the
//! impact-point error `Δx` and the focal-length error `Δf` as inputs. Here
//! `Δx` is what the parameter errors do to the offset `x − cx` at a fixed
//! measured point (a centre error moves it by about `Δcx`, distortion errors
//! by their correction's change), computed with the full model.
//!
//! The *full-model* error at a measured point `m` for parameter errors `Δθ`
//! is `Δα = α(θ + Δθ; m) − α(θ; m)` per axis (the whole chain of
//! [`crate::aoa`], no linearisation), the angle between the two rays, and the
//! position error on a plane parallel to the sensor at distance `S`:
//! `ΔX = S (tan αx' − tan αx) = S (a' − a)`, `ΔY = S (b' − b)`.
//! Radians and millimetres.

use nalgebra::{Vector2, Vector3};
use psdcal_model::{Model, Param, SensorModel};

use crate::aoa::angle_of_arrival;
use crate::error::{finite, LocateError};

/// (P40): `∂α/∂x = f / (f² + x²)`, rad/mm.
pub fn paper_sensitivity_point(f: f64, x: f64) -> f64 {
    f / (f * f + x * x)
}

/// (P41), signed: `∂α/∂f = −x / (f² + x²)`, rad/mm.
pub fn paper_sensitivity_focal(f: f64, x: f64) -> f64 {
    -x / (f * f + x * x)
}

/// (P42): `ε_α = |f/(f² + x²)| |Δx| + |x/(f² + x²)| |Δf|`, rad.
///
/// ```
/// use psdcal_locate::paper_aoa_error;
///
/// // Lens 1 (f = 25 mm) at the centre: only the point error counts, Δx / f.
/// assert!((paper_aoa_error(25.0, 0.0, 0.01, 0.1) - 0.01 / 25.0).abs() < 1e-18);
/// ```
pub fn paper_aoa_error(f: f64, x: f64, dx: f64, df: f64) -> f64 {
    paper_sensitivity_point(f, x).abs() * dx.abs() + paper_sensitivity_focal(f, x).abs() * df.abs()
}

/// Errors of some model parameters (`Δθ`), in each parameter's unit.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParameterErrors {
    entries: Vec<(Param, f64)>,
}

impl ParameterErrors {
    /// Errors of the given parameters; each parameter at most once, finite.
    pub fn new(entries: Vec<(Param, f64)>) -> Result<Self, LocateError> {
        for (i, (p, v)) in entries.iter().enumerate() {
            finite(*v, "parameter error")?;
            if entries[..i].iter().any(|(q, _)| q == p) {
                return Err(LocateError::InvalidInput {
                    what: "parameter errors",
                    reason: format!("'{p}' is given twice"),
                });
            }
        }
        Ok(Self { entries })
    }

    /// The errors, in the order given.
    pub fn entries(&self) -> &[(Param, f64)] {
        &self.entries
    }

    /// The error of `p` (0 when not given).
    pub fn get(&self, p: Param) -> f64 {
        self.entries
            .iter()
            .find(|(q, _)| *q == p)
            .map_or(0.0, |(_, v)| *v)
    }

    /// `θ + Δθ`.
    pub fn apply(&self, model: &SensorModel) -> SensorModel {
        let mut m = *model;
        for (p, v) in &self.entries {
            m.set(*p, m.get(*p) + v);
        }
        m
    }
}

/// What parameter errors do to the angle of arrival of one measured point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AoaDeviation {
    /// `(αx, αy)` with the reference model, rad.
    pub alpha: Vector2<f64>,
    /// `α(θ + Δθ) − α(θ)` per axis, rad.
    pub alpha_error: Vector2<f64>,
    /// Angle between the two rays, rad.
    pub ray_angle: f64,
    /// `(ΔX, ΔY)` on the plane parallel to the sensor at the given distance, mm.
    pub position_error: Vector2<f64>,
}

/// The full-model deviation of the angle of arrival of `measured` when the
/// parameters are off by `errors`, and of the position at `distance_mm`.
///
/// ```
/// use nalgebra::Vector2;
/// use psdcal_locate::{aoa_deviation, ParameterErrors};
/// use psdcal_model::{Param, SensorModel};
///
/// let errors = ParameterErrors::new(vec![(Param::F, 0.05), (Param::Cx, 0.01)]).unwrap();
/// let d = aoa_deviation(&SensorModel::paper_lens1(), &errors, &Vector2::new(3.0, 0.0), 5000.0).unwrap();
/// // A few hundredths of a degree, a few cm at 5 m.
/// assert!(d.alpha_error.x.abs().to_degrees() < 0.1);
/// assert!(d.position_error.norm() < 50.0);
/// ```
pub fn aoa_deviation(
    model: &SensorModel,
    errors: &ParameterErrors,
    measured: &Vector2<f64>,
    distance_mm: f64,
) -> Result<AoaDeviation, LocateError> {
    check_distance(distance_mm)?;
    let chains = Chains::new(model, errors);
    deviation(&chains, measured, distance_mm)
}

/// A model and its perturbed copy as chains (built once for a map's cells).
pub(crate) struct Chains {
    reference: SensorModel,
    perturbed: SensorModel,
    reference_chain: Model,
    perturbed_chain: Model,
}

impl Chains {
    pub(crate) fn new(model: &SensorModel, errors: &ParameterErrors) -> Self {
        let perturbed = errors.apply(model);
        Self {
            reference: *model,
            perturbed,
            reference_chain: Model::standard(model),
            perturbed_chain: Model::standard(&perturbed),
        }
    }
}

/// [`aoa_deviation`] of prepared chains (the distance already checked).
pub(crate) fn deviation(
    chains: &Chains,
    measured: &Vector2<f64>,
    distance_mm: f64,
) -> Result<AoaDeviation, LocateError> {
    let reference = angle_of_arrival(&chains.reference_chain, measured)?;
    let perturbed = angle_of_arrival(&chains.perturbed_chain, measured)?;
    let (u, v): (Vector3<f64>, Vector3<f64>) = (
        reference.direction.into_inner(),
        perturbed.direction.into_inner(),
    );
    Ok(AoaDeviation {
        alpha: reference.alpha,
        alpha_error: perturbed.alpha - reference.alpha,
        ray_angle: u.cross(&v).norm().atan2(u.dot(&v)),
        position_error: (perturbed.ray_ab - reference.ray_ab) * distance_mm,
    })
}

/// The paper's (P42) per axis at a measured point: `f` and the offsets
/// `x − cx`, `y − cy` of the reference model; `Δf` from `errors`, `Δx`,
/// `Δy` the full model's change of those offsets at the same measured point.
pub fn paper_aoa_error_at(
    model: &SensorModel,
    errors: &ParameterErrors,
    measured: &Vector2<f64>,
) -> Result<Vector2<f64>, LocateError> {
    paper_error_at(&Chains::new(model, errors), measured)
}

/// [`paper_aoa_error_at`] of prepared chains.
pub(crate) fn paper_error_at(
    chains: &Chains,
    measured: &Vector2<f64>,
) -> Result<Vector2<f64>, LocateError> {
    let reference = angle_of_arrival(&chains.reference_chain, measured)?;
    let other = angle_of_arrival(&chains.perturbed_chain, measured)?;
    let k = &chains.reference.intrinsics;
    let kp = &chains.perturbed.intrinsics;
    let offset = reference.ideal - Vector2::new(k.cx, k.cy);
    let offset_perturbed = other.ideal - Vector2::new(kp.cx, kp.cy);
    let d = offset_perturbed - offset;
    let df = kp.f - k.f;
    Ok(Vector2::new(
        paper_aoa_error(k.f, offset.x, d.x, df),
        paper_aoa_error(k.f, offset.y, d.y, df),
    ))
}

pub(crate) fn check_distance(distance_mm: f64) -> Result<(), LocateError> {
    finite(distance_mm, "distance")?;
    if distance_mm > 0.0 {
        Ok(())
    } else {
        Err(LocateError::InvalidInput {
            what: "distance",
            reason: format!("{distance_mm} mm; expected a positive distance"),
        })
    }
}
