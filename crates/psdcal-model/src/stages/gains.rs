//! The channel gains, the stage that acts first, on the four electrode
//! amplitudes (docs/model.md §1, the paper's (P1)–(P2) and (P43)).
//!
//! Amplitudes measured through channels of relative gains `g_k = K_k/K_x1`
//! are divided by them, `w_k = V_k / g_k`, before the pin-cushion formulas
//! give the impact point; `∂p/∂g_k = −(∂p/∂w_k) w_k / g_k`
//! ([`crate::psd::impact_point_gain_jacobian`]). Parameters `g_x2, g_y1,
//! g_y2` (dimensionless; `g_x1 = 1`).

use nalgebra::{Matrix2x3, Vector2};

use crate::psd::{impact_point_gain_jacobian, impact_point_with_gains};
use crate::stage::ParameterInfo;
use crate::{Amplitudes, ChannelGains, ModelError, PsdGeometry};

/// Names of the gain parameters, in block order.
pub const GAIN_NAMES: [&str; 3] = ["g_x2", "g_y1", "g_y2"];

/// The gains stage: amplitudes → impact point, for a PSD of given geometry.
#[derive(Debug, Clone, PartialEq)]
pub struct Gains {
    /// The PSD's active area.
    pub geometry: PsdGeometry,
}

impl Gains {
    /// Stage identifier in calibration files.
    pub const KIND: &'static str = "gains";

    /// The stage for a PSD of `geometry`.
    pub fn new(geometry: PsdGeometry) -> Self {
        Self { geometry }
    }

    /// The parameter block `g_x2, g_y1, g_y2`.
    pub fn parameters() -> Vec<ParameterInfo> {
        GAIN_NAMES
            .iter()
            .map(|n| ParameterInfo::new(*n, "1", 1.0, 1e-2))
            .collect()
    }

    /// The gains of a parameter block.
    pub fn gains(params: &[f64]) -> ChannelGains {
        ChannelGains {
            x2: params[0],
            y1: params[1],
            y2: params[2],
        }
    }

    /// The impact point of `amplitudes` (no Jacobian).
    pub fn apply(
        &self,
        params: &[f64],
        amplitudes: &Amplitudes,
    ) -> Result<Vector2<f64>, ModelError> {
        impact_point_with_gains(&self.geometry, amplitudes, &Self::gains(params))
    }

    /// The impact point and its Jacobian with respect to the gains (2×3).
    pub fn apply_with_jacobian(
        &self,
        params: &[f64],
        amplitudes: &Amplitudes,
    ) -> Result<(Vector2<f64>, Matrix2x3<f64>), ModelError> {
        impact_point_gain_jacobian(&self.geometry, amplitudes, &Self::gains(params))
    }

    /// Example blocks for the shared suite.
    pub fn example_parameters() -> Vec<Vec<f64>> {
        vec![vec![1.0, 1.0, 1.0], vec![1.01, 0.985, 1.02]]
    }
}
