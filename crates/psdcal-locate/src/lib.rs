//! # psdcal-locate
//!
//! What a calibrated PSD sensor is for: the **angle of arrival** of an
//! emitter's light, the emitter's **position**, and how uncertain both are
//! (docs/model.md §5, after Rodríguez-Navarro et al., *Sensors* 2016, Section
//! 3.4, (P39)–(P42), Figure 9).
//!
//! - [`aoa`]: measured point → ideal point → normalised ray `(a, b)` →
//!   `αx = atan a`, `αy = atan b` (P39), with analytic Jacobians;
//! - [`uncertainty`]: the calibration's covariance and the point noise
//!   propagated to the ray and the angles;
//! - [`calibrated_sensor`]: a [`CalibratedSensor`] (model, active area, gains,
//!   covariance) answering one measurement (point or electrode amplitudes);
//! - [`plane`]: the position on a plane parallel to the sensor at distance
//!   `S` (`X = S tan αx`, `Y = S tan αy`) or on a general plane, with its
//!   3-D covariance;
//! - [`mod@triangulate`] and [`rig`]: the position from two or more sensors
//!   with known poses in a world frame (least-squares ray intersection);
//! - [`track_filter`]: a constant-velocity Kalman filter of the windows'
//!   positions over time, with gating and re-initialisation;
//! - [`sensitivity`] and [`maps`]: the paper's small-angle sensitivity
//!   (P40)–(P42), the full-model error, and error maps over the sensor area;
//! - [`calibration_diff`]: two calibrations of one sensor compared in
//!   angles over the active area, with the combined σ;
//! - [`camera_fit`] and [`opencv_model`]: the sensor as OpenCV's rational
//!   camera model, fitted over the valid region, with the conversion's error;
//! - [`evaluate`]: positions and angles against the truth by the standard
//!   metrics (mean, median, RMS, 75th/95th percentiles, CE95/SE95, bias,
//!   the fraction inside the 95 % covariance region).
//!
//! Frames as in CONVENTIONS.md (sensor: origin at the PSD's electrical
//! centre, `z` along the optical axis towards the scene); poses are named
//! `a_from_b`. Millimetres and radians throughout; degrees belong to the
//! user interface. Nothing here panics or returns NaN on user input: what
//! cannot be answered is a [`LocateError`] with a [`LocateError::status`]
//! code, and answers that deserve care carry a [`Caution`].
//!
//! ```
//! use nalgebra::Vector2;
//! use psdcal_locate::{CalibratedSensor, LocateOptions, Measurement, Plane};
//! use psdcal_model::{PsdGeometry, SensorModel};
//!
//! let sensor = CalibratedSensor::new(SensorModel::paper_lens2(), PsdGeometry::default());
//! let options = LocateOptions { point_sigma_mm: 1e-3, ..LocateOptions::default() };
//! let m = Measurement::Point(Vector2::new(1.2, -0.4));
//! let aoa = sensor.aoa(&m, &options).unwrap();
//! println!("αx = {:.4}°, αy = {:.4}°", aoa.aoa.alpha.x.to_degrees(), aoa.aoa.alpha.y.to_degrees());
//! let at = sensor.locate_on_plane(&m, &Plane::parallel(5000.0).unwrap(), &options).unwrap();
//! assert_eq!(at.intersection.position.z, 5000.0);
//! assert!(at.cautions.is_empty());
//! ```
#![warn(missing_docs)]

pub mod aoa;
pub mod calibrated_sensor;
pub mod calibration_diff;
pub mod camera_fit;
pub mod caution;
mod error;
pub mod evaluate;
pub mod maps;
pub mod opencv_model;
pub mod plane;
pub mod psd_map;
pub mod rig;
pub mod sensitivity;
mod sensor_chains;
pub mod track_filter;
pub mod triangulate;
pub mod uncertainty;

pub use aoa::{
    alpha_from_ray, angle_of_arrival, angle_of_arrival_with_jacobians, measured_from_ray,
    ray_of_point, AngleOfArrival, AoaJacobians,
};
pub use calibrated_sensor::{
    AoaEstimate, CalibratedSensor, LocateOptions, MeasuredPoint, Measurement, PlaneLocation,
};
pub use calibration_diff::{diff_calibrations, CalibrationDiff, DiffPoint, DiffValues};
pub use camera_fit::{fit_opencv, CameraFit, CameraFitOptions, OpenCvKind};
pub use caution::{status_of, Caution};
pub use error::LocateError;
pub use evaluate::{
    evaluate_angles, evaluate_positions, percentile, percentile_with_failures, with_failures,
    AngleEvaluation, AnglePair, ErrorStats, FailureStats, PositionEvaluation, PositionPair,
    CHI2_95_2D, CHI2_95_3D,
};
pub use maps::{error_map, ErrorMap, ErrorSource, MapCell, MapOptions, MapValues, MAX_GRID};
pub use opencv_model::{OpenCv8, OPENCV8_LEN, OPENCV8_NAMES};
pub use plane::{intersect_plane, Plane, PlaneIntersection};
pub use psd_map::{MapCorrection, SensorPsdMap};
pub use rig::{Rig, RigLocation, RigSensor};
pub use sensitivity::{
    aoa_deviation, paper_aoa_error, paper_aoa_error_at, paper_sensitivity_focal,
    paper_sensitivity_point, AoaDeviation, ParameterErrors,
};
pub use track_filter::{CvFilter, CvOptions, CvState, FilterStep, TrackFilter};
pub use triangulate::{triangulate, Triangulation, WorldRay};
pub use uncertainty::{
    point_noise_covariance, propagate, sigmas_and_correlation, CovarianceError, ParameterCovariance,
};
