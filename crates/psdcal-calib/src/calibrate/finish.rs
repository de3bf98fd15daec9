//! What a calibration checks and settles once its fit is done, so that it
//! leaves psdcal-calib finished (docs/model.md §8.2–8.3):
//!
//! - **Domain.** Before the fit, every measured point must lie inside the
//!   domain of the model's first stage when that stage has one (a PSD map is
//!   known only inside its scan's hull: [`Stage::contains_input`]);
//!   otherwise [`CalibError::DataOutsideDomain`].
//! - **Valid region.** After the fit, every point (with fitted gains, the
//!   point recomputed from its amplitudes through them) must lie inside the
//!   valid region of the fitted correction; otherwise
//!   [`CalibError::DataOutsideValidRegion`]: past a fold the model has no
//!   unique answer.
//! - **A block with a known covariance.** A block held fixed with
//!   [`CalibrateOptions::fixed_covariance`] has it carried into the
//!   estimate's, `C_θ + G C_m Gᵀ` ([`carry_fixed_covariance`]); a block
//!   freed with [`CalibrateOptions::prior`] is split off the joint
//!   covariance, which keeps the other parameters only. Either way the
//!   result's [`CalibrationResult::block`] holds the block's values, its
//!   covariance with the estimate (`cross`, block rows × estimate columns)
//!   and, when refined, its own.

use psdcal_model::{ParameterCovariance, RegionEnd, ValidRegion};

use crate::calibrate::options::CalibrateOptions;
use crate::calibrate::result::{BlockCovariance, CalibrationResult};
use crate::data::{CalibrationData, DataPoint};
use crate::error::CalibError;
use crate::uncertainty::carried::carry_fixed_covariance;

/// Every measured point `(image, point, measured)` of `data`, in order.
fn measured_points(data: &CalibrationData) -> Vec<DataPoint> {
    data.images
        .iter()
        .enumerate()
        .flat_map(|(image, im)| {
            im.points
                .iter()
                .enumerate()
                .map(move |(point, obs)| DataPoint {
                    image,
                    point,
                    measured: obs.measured,
                })
        })
        .collect()
}

/// Refuses data outside the domain of the first stage of `options.base`.
pub(crate) fn check_data_in_domain(
    data: &CalibrationData,
    options: &CalibrateOptions,
) -> Result<(), CalibError> {
    let Some(first) = options.base.stages().first() else {
        return Ok(());
    };
    if !first.has_domain() {
        return Ok(());
    }
    let points = measured_points(data);
    let outside: Vec<&DataPoint> = points
        .iter()
        .filter(|p| !first.contains_input(&p.measured))
        .collect();
    match outside.first() {
        None => Ok(()),
        Some(first) => Err(CalibError::DataOutsideDomain {
            outside: outside.len(),
            points: points.len(),
            first: **first,
        }),
    }
}

/// Refuses a result whose valid region does not contain the measured
/// points it was fitted to (with fitted gains, the points recomputed from
/// the amplitudes through them).
pub(crate) fn check_data_in_region(
    result: &CalibrationResult,
    data: &CalibrationData,
) -> Result<(), CalibError> {
    let mut points = measured_points(data);
    for p in &mut points {
        let amplitudes = data
            .amplitudes
            .as_ref()
            .and_then(|a| a.get(p.image)?.get(p.point));
        if let (Some(_), Some(a)) = (result.model.gains_stage(), amplitudes) {
            p.measured = result
                .model
                .measured_from_amplitudes(a)
                .unwrap_or(p.measured);
        }
    }
    refuse_points_outside(&result.valid_region, &points)
}

/// [`CalibError::DataOutsideValidRegion`] when a point lies outside
/// `region`.
fn refuse_points_outside(region: &ValidRegion, points: &[DataPoint]) -> Result<(), CalibError> {
    let outside: Vec<_> = points
        .iter()
        .filter_map(|p| region.check(&p.measured).err().map(|o| (p, o)))
        .collect();
    let Some((first, o)) = outside.first() else {
        return Ok(());
    };
    if o.end == RegionEnd::DomainEdge {
        // Points moved by the fitted gains off the first stage's domain.
        return Err(CalibError::DataOutsideDomain {
            outside: outside.len(),
            points: points.len(),
            first: **first,
        });
    }
    Err(CalibError::DataOutsideValidRegion {
        outside: outside.len(),
        points: points.len(),
        fold_mm: region.nearest_fold_mm().unwrap_or(o.limit_mm),
        first: **first,
        distance_mm: o.distance_mm,
        limit_mm: o.limit_mm,
    })
}

/// The block with a known covariance, settled (module documentation).
pub(crate) fn settle_block(
    result: &mut CalibrationResult,
    data: &CalibrationData,
    options: &CalibrateOptions,
) -> Result<(), CalibError> {
    result.block = match (&options.prior, &options.fixed_covariance) {
        (Some(prior), _) => Some(split_prior_block(result, prior)?),
        (None, Some(fixed)) => Some(carry_fixed_block(result, data, options, fixed)?),
        (None, None) => None,
    };
    Ok(())
}

/// A covariance's sub-block failing is an internal inconsistency.
fn inconsistent(e: impl std::fmt::Display) -> CalibError {
    CalibError::InvalidInput {
        reason: format!("the calibration's covariance: {e}"),
    }
}

/// The refined block split off the joint covariance, which is narrowed to
/// the other estimated parameters.
fn split_prior_block(
    result: &mut CalibrationResult,
    prior: &ParameterCovariance,
) -> Result<BlockCovariance, CalibError> {
    let names = prior.names();
    let joint = &result.covariance.parameters;
    let others: Vec<String> = joint
        .names()
        .iter()
        .filter(|n| !names.contains(n))
        .cloned()
        .collect();
    let matrix = joint.sub(names).map_err(inconsistent)?.matrix().clone();
    let cross = joint.cross(names, &others).map_err(inconsistent)?;
    let parameters = block_values(result, names)?;
    result.covariance.parameters = joint.sub(&others).map_err(inconsistent)?;
    Ok(BlockCovariance {
        parameters,
        matrix: Some(matrix),
        cross,
    })
}

/// The fixed block's covariance carried into the estimate's.
fn carry_fixed_block(
    result: &mut CalibrationResult,
    data: &CalibrationData,
    options: &CalibrateOptions,
    fixed: &ParameterCovariance,
) -> Result<BlockCovariance, CalibError> {
    let carried = carry_fixed_covariance(
        data,
        &result.model,
        &result.poses,
        &options.refine,
        &result.covariance.parameters,
        fixed,
    )?;
    result.covariance.parameters = carried.parameters;
    Ok(BlockCovariance {
        parameters: block_values(result, fixed.names())?,
        matrix: None,
        cross: carried.cross,
    })
}

/// The block's `(name, value)` in the fitted model.
fn block_values(
    result: &CalibrationResult,
    names: &[String],
) -> Result<Vec<(String, f64)>, CalibError> {
    names
        .iter()
        .map(|n| {
            result
                .model
                .get(n)
                .map(|v| (n.clone(), v))
                .ok_or_else(|| inconsistent(format!("the model has no '{n}'")))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector2;
    use psdcal_model::{PsdGeometry, SensorModel};

    use super::*;

    fn at(image: usize, point: usize, x: f64, y: f64) -> DataPoint {
        DataPoint {
            image,
            point,
            measured: Vector2::new(x, y),
        }
    }

    /// Data past the fold of k1 = −0.02 mm⁻² about (0.5, −0.7) (r* =
    /// 1/√(3 · 0.02) = 4.08 mm) are refused with the count and the first
    /// point; data inside pass, and a non-folding model takes them all.
    #[test]
    fn data_past_the_fold_are_refused() {
        let mut model = SensorModel::pinhole(8.0, 0.5, -0.7);
        model.distortion.k1 = -0.02;
        let region = ValidRegion::of_sensor_model(&model, &PsdGeometry::default());
        let inside = vec![at(0, 0, 0.5, -0.7), at(0, 1, 3.0, 1.0)];
        assert!(refuse_points_outside(&region, &inside).is_ok());
        let mut data = inside.clone();
        data.push(at(1, 0, -4.5, 4.5));
        data.push(at(2, 0, 4.5, -4.5));
        let e = refuse_points_outside(&region, &data).unwrap_err();
        let CalibError::DataOutsideValidRegion {
            outside,
            points,
            fold_mm,
            first,
            distance_mm,
            ..
        } = e
        else {
            panic!("{e}")
        };
        assert_eq!((outside, points), (2, 4));
        assert!((fold_mm - 1.0 / (3.0f64 * 0.02).sqrt()).abs() < 1e-9);
        assert_eq!((first.image, first.point), (1, 0));
        // |(-4.5, 4.5) - (0.5, -0.7)| = √(25 + 27.04).
        assert!((distance_mm - 52.04f64.sqrt()).abs() < 1e-12);
        let plain =
            ValidRegion::of_sensor_model(&SensorModel::paper_lens2(), &PsdGeometry::default());
        assert!(refuse_points_outside(&plain, &data).is_ok());
    }
}
