//! # psdcal-model
//!
//! The mathematical model of a pin-cushion position-sensitive device (PSD)
//! behind a lens, as specified in psdcal's `docs/model.md` §1–3 (after
//! Rodríguez-Navarro et al., *Sensors* 2016, 16(9), 1484):
//!
//! - [`psd`]: electrode amplitudes ↔ impact point, channel gains (P1, P2, P43);
//! - [`stage`], [`stages`], [`model`], [`model_projection`]: the model, one
//!   chain of stages with runtime-sized, named parameter blocks (docs/model.md
//!   §8): PSD and lens distortion (P7–P16), the pinhole with one focal length
//!   and optional skew (P4), template plane ↔ measured point (P5, P29), each
//!   with analytic Jacobians; what calibration estimates and every map uses;
//! - [`params`]: [`SensorModel`], the standard chain's parameters by name
//!   ([`Param`]), a view converted to and from [`Model`] ([`Model::standard`],
//!   [`Model::sensor_model`]);
//! - [`distortion`]: the inverse of the distortion (ideal → measured point,
//!   Newton's method);
//! - [`pose`]: Rodrigues poses and their derivatives (P3);
//! - [`covariance`]: [`ParameterCovariance`], the one covariance type (named
//!   parameters, validated symmetric matrix);
//! - [`hull`]: [`ConvexHull`], the domain of a stage fitted to a scan;
//! - [`fit`]: what every fit shares: [`CostKind`], [`MIN_IMAGES`];
//! - [`valid_region`]: where the measured → ideal map is one-to-one
//!   (docs/model.md §8.2), a radius per ray from the optical centre.
//!
//! Millimetres everywhere, radians inside. See `CONVENTIONS.md` at the root of
//! the repository for symbols and frames.
#![warn(missing_docs)]

// The paper's simulated set-up as psdcal fixes it (docs/model.md §7).
pub mod paper_setup;

pub mod covariance;
pub mod diagnostic;
pub mod distortion;
mod error;
pub mod fit;
pub mod hull;
pub mod model;
pub mod model_projection;
pub mod params;
pub mod pose;
pub mod psd;
pub mod stage;
pub mod stages;
pub mod valid_region;

pub use covariance::{CovarianceError, ParameterCovariance};
pub use diagnostic::{Diagnostic, DiagnosticCode, Severity};
pub use error::ModelError;
pub use fit::{CostKind, MIN_IMAGES, MIN_POINTS_PER_IMAGE};
pub use hull::ConvexHull;
pub use model::{ChainJacobian, Model};
pub use model_projection::{PointJacobians, PoseJacobians};
pub use params::{Distortion, Intrinsics, Param, SensorModel, UnknownParam, N_PARAMS};
pub use pose::{Pose, RotationJacobian, N_POSE};
pub use psd::{Amplitudes, ChannelGains, PsdGeometry};
pub use stage::{ParameterInfo, Stage, StageJacobian};
pub use valid_region::{OutsideRegion, RegionEnd, ValidRegion};
