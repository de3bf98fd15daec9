//! Error maps over the sensor area (the paper's Figure 9, Section 3.4): at
//! every point of a grid over the PSD's active area, the error of the angle
//! of arrival and of the position on a plane parallel to the sensor at
//! distance `S` (default 5 m).
//!
//! Grid: `N × N` measured points `(x, y)` from `−L/2` to `+L/2` on each axis
//! (edges included), row-major with `y` outer, mm, sensor frame.
//!
//! Two sources of error:
//!
//! - *Parameter errors* `Δθ` (e.g. the paper's `|mean − ideal| + 2·std`):
//!   the full model, no linearisation ([`crate::sensitivity::aoa_deviation`]):
//!   `|Δαx|`, `|Δαy|`, the angle between the rays, `|ΔX| = S |a' − a|`,
//!   `|ΔY| = S |b' − b|` and `√(ΔX² + ΔY²)`. The paper's small-angle form
//!   (P42) can be added alongside for comparison.
//! - *A calibration's covariance* at `k` σ ([`crate::uncertainty`]):
//!   `k σ_αx`, `k σ_αy`, `k √(σ²_αx + σ²_αy)`, and on the plane
//!   `Σ_XY = S² Σ_ab`: `k σ_X`, `k σ_Y`, `k √(σ²_X + σ²_Y)`.
//!
//! A grid point where the model is not valid — outside its valid region
//! (docs/model.md §8.2: past the first fold of the correction from the
//! optical centre) or where the correction folds over — is kept with its
//! reason (status `outside_valid_region`), never with a made-up number.

use nalgebra::Vector2;
use psdcal_model::{PsdGeometry, SensorModel, ValidRegion};

use crate::calibrated_sensor::{check_region, CalibratedSensor, LocateOptions, Measurement};
use crate::error::{exceeds, finite, LocateError};
use crate::sensitivity::{check_distance, deviation, paper_error_at, Chains, ParameterErrors};
use crate::uncertainty::ParameterCovariance;

/// Largest grid side accepted.
pub const MAX_GRID: usize = 1001;

/// Options of [`error_map`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapOptions {
    /// Grid points per side (2 to [`MAX_GRID`]).
    pub grid: usize,
    /// Distance `S` of the plane parallel to the sensor, mm.
    pub distance_mm: f64,
    /// Also evaluate the paper's small-angle form (P42) (parameter errors only).
    pub paper_form: bool,
}

impl Default for MapOptions {
    /// 41 × 41 points, S = 5 m (Figure 9), no paper form.
    fn default() -> Self {
        Self {
            grid: 41,
            distance_mm: 5000.0,
            paper_form: false,
        }
    }
}

/// Where the errors come from.
#[derive(Debug, Clone, PartialEq)]
pub enum ErrorSource {
    /// Given parameter errors, through the full model.
    Parameters(ParameterErrors),
    /// A calibration's covariance, at `k` standard deviations.
    Covariance {
        /// The covariance.
        covariance: ParameterCovariance,
        /// How many σ.
        k: f64,
    },
}

/// The errors at one grid point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapValues {
    /// `(αx, αy)` with the reference model, rad.
    pub alpha: Vector2<f64>,
    /// AoA error per axis (≥ 0), rad.
    pub aoa_error: Vector2<f64>,
    /// Combined AoA error (angle between the rays, or `k√(σ²_αx + σ²_αy)`), rad.
    pub aoa_error_total: f64,
    /// Position error per axis on the plane (≥ 0), mm.
    pub position_error: Vector2<f64>,
    /// Combined position error, mm.
    pub position_error_total: f64,
    /// The paper's (P42) per axis, rad, when asked for.
    pub paper_aoa_error: Option<Vector2<f64>>,
}

/// One grid point.
#[derive(Debug, Clone, PartialEq)]
pub struct MapCell {
    /// The measured point, mm.
    pub measured: Vector2<f64>,
    /// Its errors, or why there are none.
    pub values: Result<MapValues, LocateError>,
}

/// An error map.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorMap {
    /// Grid points per side.
    pub grid: usize,
    /// Distance of the plane, mm.
    pub distance_mm: f64,
    /// `grid²` cells, row-major, `y` outer.
    pub cells: Vec<MapCell>,
}

impl ErrorMap {
    fn values(&self) -> impl Iterator<Item = &MapValues> {
        self.cells.iter().filter_map(|c| c.values.as_ref().ok())
    }

    /// Number of cells with values.
    pub fn answered(&self) -> usize {
        self.values().count()
    }

    /// Largest combined AoA error, rad (`None` when no cell has values).
    pub fn max_aoa_error(&self) -> Option<f64> {
        self.values().map(|v| v.aoa_error_total).reduce(f64::max)
    }

    /// Largest combined position error, mm.
    pub fn max_position_error(&self) -> Option<f64> {
        self.values()
            .map(|v| v.position_error_total)
            .reduce(f64::max)
    }
}

/// The error map of `model` over `geometry`'s active area.
///
/// ```
/// use psdcal_locate::{error_map, ErrorSource, MapOptions, ParameterErrors};
/// use psdcal_model::{Param, PsdGeometry, SensorModel};
///
/// let errors = ParameterErrors::new(vec![(Param::F, 0.1), (Param::Cx, 0.02)]).unwrap();
/// let map = error_map(
///     &SensorModel::paper_lens1(),
///     &PsdGeometry::default(),
///     &ErrorSource::Parameters(errors),
///     &MapOptions { grid: 5, ..MapOptions::default() },
/// )
/// .unwrap();
/// assert_eq!(map.cells.len(), 25);
/// assert_eq!(map.answered(), 25);
/// assert!(map.max_position_error().unwrap() < 100.0); // mm at 5 m
/// ```
pub fn error_map(
    model: &SensorModel,
    geometry: &PsdGeometry,
    source: &ErrorSource,
    options: &MapOptions,
) -> Result<ErrorMap, LocateError> {
    model.validate()?;
    check_distance(options.distance_mm)?;
    if !(2..=MAX_GRID).contains(&options.grid) {
        return Err(LocateError::InvalidInput {
            what: "grid",
            reason: format!("{} points per side; expected 2 to {MAX_GRID}", options.grid),
        });
    }
    for side in [geometry.lx, geometry.ly] {
        finite(side, "sensor size")?;
        if !exceeds(side, 0.0) {
            return Err(LocateError::InvalidInput {
                what: "sensor size",
                reason: format!("{side} mm; expected a positive size"),
            });
        }
    }
    let sensor = match source {
        ErrorSource::Covariance { covariance, k } => {
            finite(*k, "k")?;
            if !exceeds(*k, 0.0) {
                return Err(LocateError::InvalidInput {
                    what: "k",
                    reason: format!("{k}; expected a positive number of standard deviations"),
                });
            }
            if options.paper_form {
                return Err(LocateError::InvalidInput {
                    what: "map options",
                    reason: "the paper's form (P42) needs parameter errors, not a covariance"
                        .into(),
                });
            }
            Some(CalibratedSensor::new(*model, *geometry).with_covariance(covariance.clone()))
        }
        ErrorSource::Parameters(_) => None,
    };
    let region = match &sensor {
        Some(s) => s.valid_region.clone(),
        None => ValidRegion::of_sensor_model(model, geometry),
    };
    let chains = match source {
        ErrorSource::Parameters(errors) => Some(Chains::new(model, errors)),
        ErrorSource::Covariance { .. } => None,
    };
    let n = options.grid;
    let last = (n - 1) as f64;
    let s = options.distance_mm;
    let mut cells = Vec::with_capacity(n * n);
    for iy in 0..n {
        for ix in 0..n {
            let measured = Vector2::new(
                geometry.lx * (ix as f64 / last - 0.5),
                geometry.ly * (iy as f64 / last - 0.5),
            );
            let values = check_region(&region, &measured).and_then(|()| match (&chains, &sensor) {
                (Some(chains), _) => parameter_cell(chains, &measured, s, options.paper_form),
                (None, Some(sensor)) => match source {
                    ErrorSource::Covariance { k, .. } => covariance_cell(sensor, &measured, s, *k),
                    ErrorSource::Parameters(_) => unreachable_cell(),
                },
                (None, None) => unreachable_cell(),
            });
            cells.push(MapCell { measured, values });
        }
    }
    Ok(ErrorMap {
        grid: n,
        distance_mm: s,
        cells,
    })
}

fn unreachable_cell() -> Result<MapValues, LocateError> {
    Err(LocateError::InvalidInput {
        what: "map",
        reason: "no sensor for the covariance".into(),
    })
}

fn parameter_cell(
    chains: &Chains,
    measured: &Vector2<f64>,
    distance_mm: f64,
    paper_form: bool,
) -> Result<MapValues, LocateError> {
    let d = deviation(chains, measured, distance_mm)?;
    let paper_aoa_error = if paper_form {
        Some(paper_error_at(chains, measured)?)
    } else {
        None
    };
    Ok(MapValues {
        alpha: d.alpha,
        aoa_error: d.alpha_error.abs(),
        aoa_error_total: d.ray_angle,
        position_error: d.position_error.abs(),
        position_error_total: d.position_error.norm(),
        paper_aoa_error,
    })
}

fn covariance_cell(
    sensor: &CalibratedSensor,
    measured: &Vector2<f64>,
    distance_mm: f64,
    k: f64,
) -> Result<MapValues, LocateError> {
    let est = sensor.aoa(&Measurement::Point(*measured), &LocateOptions::default())?;
    let ca = est.alpha_covariance_calibration();
    let cr = est.ray_covariance_calibration;
    let sd = |v: f64| v.max(0.0).sqrt();
    Ok(MapValues {
        alpha: est.aoa.alpha,
        aoa_error: Vector2::new(sd(ca[(0, 0)]), sd(ca[(1, 1)])) * k,
        aoa_error_total: k * sd(ca[(0, 0)] + ca[(1, 1)]),
        position_error: Vector2::new(sd(cr[(0, 0)]), sd(cr[(1, 1)])) * (k * distance_mm),
        position_error_total: k * distance_mm * sd(cr[(0, 0)] + cr[(1, 1)]),
        paper_aoa_error: None,
    })
}
