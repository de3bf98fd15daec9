//! # psdcal-psdmap
//!
//! The PSD's own non-linearity map fitted to a lensless scan (docs/model.md
//! §8.3): a stage moved a light spot to known positions `s_i` and the bare
//! PSD measured `m_i`; the map `m ↦ m + Σ a_k φ_k(m)` of
//! [`psdcal_model::stages::PsdMap`] is fitted to the displacements
//! `d_i = s_i − m_i` by linear least squares.
//!
//! - [`normal`]: the normal equations, accumulated row by row;
//! - [`penalty`]: the splines' second-difference smoothness penalty;
//! - [`solve`]: one penalised solve (Cholesky) and the residuals;
//! - [`robust`]: the robust scale, Huber reweighting and 5σ rejection;
//! - [`cross_validation`]: k-fold cross-validation and the
//!   one-standard-error choice;
//! - [`fit`]: [`fit_psd_map`], the whole fit with the coefficients'
//!   covariance, the cross-validated RMS and the residuals;
//! - [`mod@residual_map`]: the residuals summarised per cell.
//!
//! Millimetres inside; reports convert to µm.
#![warn(missing_docs)]

pub mod cross_validation;
mod error;
pub mod fit;
pub mod normal;
pub mod penalty;
pub mod residual_map;
pub mod robust;
pub mod solve;

pub use error::PsdMapError;
pub use fit::{fit_psd_map, CandidateResult, FitOptions, ModelChoice, PsdMapFit};
pub use residual_map::{residual_map, ResidualCell};
