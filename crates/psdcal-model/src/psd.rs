//! The pin-cushion PSD: electrode amplitudes ↔ impact point (docs/model.md §1,
//! the paper's (P1)–(P2) with the brackets corrected, and (P43)).
//!
//! Sensor frame: origin at the electrical centre, `x`, `y` along the sides,
//! millimetres. Electrodes sit at the corners: `x2 = (+,+)`, `y1 = (+,−)`,
//! `x1 = (−,−)`, `y2 = (−,+)`. With `S = Vx1 + Vx2 + Vy1 + Vy2`:
//!
//! ```text
//! x = (Lx/2) · ((Vx2 + Vy1) − (Vx1 + Vy2)) / S
//! y = (Ly/2) · ((Vx2 + Vy2) − (Vx1 + Vy1)) / S
//! ```
//!
//! Forward model (exactly inverted by the above), with `u = 2x/Lx`,
//! `v = 2y/Ly` and total photocurrent `I0`:
//!
//! ```text
//! Ix2 = I0 (1+u)(1+v)/4   Iy1 = I0 (1+u)(1−v)/4
//! Ix1 = I0 (1−u)(1−v)/4   Iy2 = I0 (1−u)(1+v)/4
//! ```
//!
//! Each channel is amplified, `V_k = K_k I_k`. Only the *relative* gains
//! `g_k = K_k / K_x1` matter to the position (the common factor cancels in the
//! ratio), so [`ChannelGains`] stores them with `g_x1 = 1` as the reference.
//! The transimpedance gain of (P43) is `K = R / (2π f R C + 1)`.

use nalgebra::{Matrix2x3, Matrix2x4, Vector2};
use serde::{Deserialize, Serialize};

use crate::ModelError;

/// Active area of the PSD, mm. Default: Hamamatsu S5991-01, 9 × 9 mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PsdGeometry {
    /// Side along x, mm.
    pub lx: f64,
    /// Side along y, mm.
    pub ly: f64,
}

impl Default for PsdGeometry {
    fn default() -> Self {
        Self { lx: 9.0, ly: 9.0 }
    }
}

/// Amplitudes of the four electrode channels (volts or any consistent unit).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Amplitudes {
    /// Channel x1, electrode at (−,−).
    pub vx1: f64,
    /// Channel x2, electrode at (+,+).
    pub vx2: f64,
    /// Channel y1, electrode at (+,−).
    pub vy1: f64,
    /// Channel y2, electrode at (−,+).
    pub vy2: f64,
}

impl From<[f64; 4]> for Amplitudes {
    /// The channels in the order `vx1, vx2, vy1, vy2`.
    fn from(a: [f64; 4]) -> Self {
        Self {
            vx1: a[0],
            vx2: a[1],
            vy1: a[2],
            vy2: a[3],
        }
    }
}

/// Gains of the four channels relative to channel x1 (`g_k = K_k / K_x1`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ChannelGains {
    /// Relative gain of channel x2.
    pub x2: f64,
    /// Relative gain of channel y1.
    pub y1: f64,
    /// Relative gain of channel y2.
    pub y2: f64,
}

impl ChannelGains {
    /// Balanced channels: every relative gain 1.
    pub const UNIT: Self = Self {
        x2: 1.0,
        y1: 1.0,
        y2: 1.0,
    };

    /// Relative gains from the four absolute gains `K_x1, K_x2, K_y1, K_y2`.
    pub fn from_absolute(k_x1: f64, k_x2: f64, k_y1: f64, k_y2: f64) -> Self {
        Self {
            x2: k_x2 / k_x1,
            y1: k_y1 / k_x1,
            y2: k_y2 / k_x1,
        }
    }

    /// Checks that every gain is finite and positive.
    pub fn validate(&self) -> Result<(), ModelError> {
        for (name, value) in [("g_x2", self.x2), ("g_y1", self.y1), ("g_y2", self.y2)] {
            if !value.is_finite() || value <= 0.0 {
                return Err(ModelError::InvalidParameter {
                    name,
                    value,
                    reason: "a channel gain must be finite and positive",
                });
            }
        }
        Ok(())
    }

    /// The gains as `[g_x2, g_y1, g_y2]` (the parameter order of CONVENTIONS.md).
    pub fn to_array(&self) -> [f64; 3] {
        [self.x2, self.y1, self.y2]
    }
}

impl Default for ChannelGains {
    fn default() -> Self {
        Self::UNIT
    }
}

impl Amplitudes {
    /// The amplitudes with the relative channel gains divided out.
    pub fn divide_gains(&self, gains: &ChannelGains) -> Self {
        Self {
            vx1: self.vx1,
            vx2: self.vx2 / gains.x2,
            vy1: self.vy1 / gains.y1,
            vy2: self.vy2 / gains.y2,
        }
    }

    /// The amplitudes multiplied by the relative channel gains (what an
    /// unbalanced amplifier stage does to balanced signals).
    pub fn apply_gains(&self, gains: &ChannelGains) -> Self {
        Self {
            vx1: self.vx1,
            vx2: self.vx2 * gains.x2,
            vy1: self.vy1 * gains.y1,
            vy2: self.vy2 * gains.y2,
        }
    }

    /// Sum of the four amplitudes (`S` of docs/model.md §1).
    pub fn total(&self) -> f64 {
        self.vx1 + self.vx2 + self.vy1 + self.vy2
    }

    fn check(&self) -> Result<(), ModelError> {
        if ![self.vx1, self.vx2, self.vy1, self.vy2]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(ModelError::NonFinite {
                what: "electrode amplitude",
            });
        }
        let total = self.total();
        if total <= 0.0 || !total.is_finite() {
            return Err(ModelError::NonPositiveTotal { total });
        }
        Ok(())
    }
}

/// Transimpedance amplifier gain `K = R / (2π f R C + 1)` (P43), in V/A for
/// `r_ohm` in Ω, `c_farad` in F and `f_hz` in Hz.
pub fn transimpedance_gain(r_ohm: f64, c_farad: f64, f_hz: f64) -> f64 {
    r_ohm / (2.0 * std::f64::consts::PI * f_hz * r_ohm * c_farad + 1.0)
}

/// Impact point (mm, sensor frame) from the four electrode amplitudes,
/// assuming balanced channels (docs/model.md §1).
pub fn impact_point(geometry: &PsdGeometry, amps: &Amplitudes) -> Result<Vector2<f64>, ModelError> {
    amps.check()?;
    let s = amps.total();
    let x = 0.5 * geometry.lx * ((amps.vx2 + amps.vy1) - (amps.vx1 + amps.vy2)) / s;
    let y = 0.5 * geometry.ly * ((amps.vx2 + amps.vy2) - (amps.vx1 + amps.vy1)) / s;
    Ok(Vector2::new(x, y))
}

/// Impact point from amplitudes measured through channels of relative gains
/// `gains`, which are divided out first.
pub fn impact_point_with_gains(
    geometry: &PsdGeometry,
    amps: &Amplitudes,
    gains: &ChannelGains,
) -> Result<Vector2<f64>, ModelError> {
    gains.validate()?;
    impact_point(geometry, &amps.divide_gains(gains))
}

/// Jacobian of the balanced impact point with respect to the four
/// amplitudes, columns in the order `vx1, vx2, vy1, vy2`:
/// `∂(x, y)/∂V_k = ((Lx/2)(sx_k − u), (Ly/2)(sy_k − v)) / S` with the
/// electrode signs `(sx_k, sy_k)`, `u = 2x/Lx`, `v = 2y/Ly`, `S = Σ V_k`.
pub fn impact_point_amplitude_jacobian(
    geometry: &PsdGeometry,
    amps: &Amplitudes,
) -> Result<(Vector2<f64>, Matrix2x4<f64>), ModelError> {
    let point = impact_point(geometry, amps)?;
    let s = amps.total();
    let u = 2.0 * point.x / geometry.lx;
    let v = 2.0 * point.y / geometry.ly;
    // Electrode signs (sx, sy) of x1, x2, y1, y2.
    let signs = [(-1.0, -1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, 1.0)];
    let mut jac = Matrix2x4::zeros();
    for (col, (sx, sy)) in signs.into_iter().enumerate() {
        jac[(0, col)] = 0.5 * geometry.lx * (sx - u) / s;
        jac[(1, col)] = 0.5 * geometry.ly * (sy - v) / s;
    }
    Ok((point, jac))
}

/// Impact point and its Jacobian with respect to the relative gains
/// `(g_x2, g_y1, g_y2)`, for amplitudes measured through those gains.
pub fn impact_point_gain_jacobian(
    geometry: &PsdGeometry,
    amps: &Amplitudes,
    gains: &ChannelGains,
) -> Result<(Vector2<f64>, Matrix2x3<f64>), ModelError> {
    gains.validate()?;
    let w = amps.divide_gains(gains);
    let (point, dp_dw) = impact_point_amplitude_jacobian(geometry, &w)?;
    // w_k = V_k / g_k, so ∂w_k/∂g_k = −w_k / g_k (channels x2, y1, y2 are
    // columns 1, 2, 3 of the amplitude Jacobian).
    let channels = [
        (1, w.vx2, gains.x2),
        (2, w.vy1, gains.y1),
        (3, w.vy2, gains.y2),
    ];
    let mut jac = Matrix2x3::zeros();
    for (col, (k, wk, gk)) in channels.into_iter().enumerate() {
        jac.set_column(col, &(dp_dw.column(k) * (-wk / gk)));
    }
    Ok((point, jac))
}

/// Forward pin-cushion model: the four electrode currents produced by a light
/// spot of total photocurrent `i0` at `point` (mm, sensor frame).
pub fn electrode_currents(geometry: &PsdGeometry, point: &Vector2<f64>, i0: f64) -> Amplitudes {
    let u = 2.0 * point.x / geometry.lx;
    let v = 2.0 * point.y / geometry.ly;
    Amplitudes {
        vx1: 0.25 * i0 * (1.0 - u) * (1.0 - v),
        vx2: 0.25 * i0 * (1.0 + u) * (1.0 + v),
        vy1: 0.25 * i0 * (1.0 + u) * (1.0 - v),
        vy2: 0.25 * i0 * (1.0 - u) * (1.0 + v),
    }
}

/// Whether `point` lies on the active area (closed rectangle centred on the
/// electrical centre).
pub fn is_on_active_area(geometry: &PsdGeometry, point: &Vector2<f64>) -> bool {
    point.x.abs() <= 0.5 * geometry.lx && point.y.abs() <= 0.5 * geometry.ly
}
