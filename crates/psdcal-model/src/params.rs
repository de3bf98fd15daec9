//! The sensor's parameters and their fixed order in parameter vectors.
//!
//! A [`SensorModel`] is everything a calibration estimates about one sensor
//! besides the poses: the pinhole intrinsics `f, cx, cy, skew` (docs/model.md §3,
//! (P4)) and the distortion coefficients `k1, k2, k3, p1, p2, l1, l2`
//! (docs/model.md §2, (P7)–(P16)). It is a named view of the standard chain's
//! parameters, not a second model: every map (distortion, projection, rays,
//! their Jacobians) is computed by [`crate::Model`], built from it with
//! [`crate::Model::standard`] (and read back with
//! [`crate::Model::sensor_model`]). Parameter vectors and Jacobian columns
//! always follow the order of [`Param::ALL`]:
//!
//! ```text
//! 0 f   1 cx   2 cy   3 skew   4 k1   5 k2   6 k3   7 p1   8 p2   9 l1   10 l2
//! ```
//!
//! `f`, `cx`, `cy` in mm; `skew` in mm (the `γ` of docs/model.md §3, same unit as
//! `f`); `k1` in mm⁻², `k2` in mm⁻⁴, `k3` in mm⁻⁶, `p1`, `p2` in mm⁻¹,
//! `l1` in mm⁻², `l2` in mm⁻⁴.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::ModelError;

/// Number of sensor parameters ([`Param::ALL`]).
pub const N_PARAMS: usize = 11;

/// One sensor parameter; its discriminant is its index in parameter vectors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Param {
    /// Focal length, mm.
    F = 0,
    /// Optical centre x, mm (sensor frame).
    Cx = 1,
    /// Optical centre y, mm (sensor frame).
    Cy = 2,
    /// Skew `γ`, mm.
    Skew = 3,
    /// Lens radial r², mm⁻².
    K1 = 4,
    /// Lens radial r⁴, mm⁻⁴.
    K2 = 5,
    /// Lens radial r⁶, mm⁻⁶.
    K3 = 6,
    /// Lens tangential, mm⁻¹.
    P1 = 7,
    /// Lens tangential, mm⁻¹.
    P2 = 8,
    /// PSD radial h², mm⁻².
    L1 = 9,
    /// PSD radial h⁴, mm⁻⁴.
    L2 = 10,
}

impl Param {
    /// Every parameter, in vector order.
    pub const ALL: [Param; N_PARAMS] = [
        Param::F,
        Param::Cx,
        Param::Cy,
        Param::Skew,
        Param::K1,
        Param::K2,
        Param::K3,
        Param::P1,
        Param::P2,
        Param::L1,
        Param::L2,
    ];

    /// Index in parameter vectors and Jacobian columns.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Param::F => "f",
            Param::Cx => "cx",
            Param::Cy => "cy",
            Param::Skew => "skew",
            Param::K1 => "k1",
            Param::K2 => "k2",
            Param::K3 => "k3",
            Param::P1 => "p1",
            Param::P2 => "p2",
            Param::L1 => "l1",
            Param::L2 => "l2",
        }
    }

    /// The unit, for reports.
    pub fn unit(self) -> &'static str {
        match self {
            Param::F | Param::Cx | Param::Cy | Param::Skew => "mm",
            Param::K1 | Param::L1 => "mm^-2",
            Param::K2 | Param::L2 => "mm^-4",
            Param::K3 => "mm^-6",
            Param::P1 | Param::P2 => "mm^-1",
        }
    }
}

impl AsRef<str> for Param {
    fn as_ref(&self) -> &str {
        self.name()
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Error of [`Param::from_str`]: the name is not a sensor parameter.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown parameter '{0}' (expected one of f, cx, cy, skew, k1, k2, k3, p1, p2, l1, l2)")]
pub struct UnknownParam(pub String);

impl FromStr for Param {
    type Err = UnknownParam;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let lower = s.trim().to_ascii_lowercase();
        Param::ALL
            .into_iter()
            .find(|p| p.name() == lower)
            .ok_or_else(|| UnknownParam(s.to_string()))
    }
}

/// Pinhole intrinsics (docs/model.md §3, (P4)): one focal length, optical centre,
/// optional skew. Millimetres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    /// Focal length, mm.
    pub f: f64,
    /// Optical centre x, mm, sensor frame (offset from the electrical centre).
    pub cx: f64,
    /// Optical centre y, mm, sensor frame.
    pub cy: f64,
    /// Skew `γ`, mm (0 unless freed).
    pub skew: f64,
}

/// Distortion coefficients (docs/model.md §2). Lens terms are centred on the
/// optical centre `(cx, cy)`, PSD terms on the electrical centre `(0, 0)`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Distortion {
    /// Lens radial r², mm⁻².
    pub k1: f64,
    /// Lens radial r⁴, mm⁻⁴.
    pub k2: f64,
    /// Lens radial r⁶, mm⁻⁶.
    pub k3: f64,
    /// Lens tangential, mm⁻¹.
    pub p1: f64,
    /// Lens tangential, mm⁻¹.
    pub p2: f64,
    /// PSD radial h², mm⁻².
    pub l1: f64,
    /// PSD radial h⁴, mm⁻⁴.
    pub l2: f64,
}

/// The full sensor model: pinhole intrinsics plus distortion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SensorModel {
    /// Pinhole intrinsics.
    pub intrinsics: Intrinsics,
    /// Distortion coefficients.
    pub distortion: Distortion,
}

impl SensorModel {
    /// A distortion-free pinhole with focal length `f` and centre `(cx, cy)`.
    pub fn pinhole(f: f64, cx: f64, cy: f64) -> Self {
        Self {
            intrinsics: Intrinsics {
                f,
                cx,
                cy,
                skew: 0.0,
            },
            distortion: Distortion::default(),
        }
    }

    /// Lens 1 of the paper's simulations (docs/model.md §7): f = 25 mm,
    /// k1 = 2e-3 mm⁻², centre (0.5, −0.7) mm.
    pub fn paper_lens1() -> Self {
        let mut m = Self::pinhole(25.0, 0.5, -0.7);
        m.distortion.k1 = 2e-3;
        m
    }

    /// Lens 2 of the paper's simulations (docs/model.md §7): f = 8 mm,
    /// k1 = 1e-2 mm⁻², k2 = 3e-5 mm⁻⁴, centre (0.5, −0.7) mm.
    pub fn paper_lens2() -> Self {
        let mut m = Self::pinhole(8.0, 0.5, -0.7);
        m.distortion.k1 = 1e-2;
        m.distortion.k2 = 3e-5;
        m
    }

    /// The paper's PSD distortion coefficient `l1` (Section 4.5), mm⁻².
    pub const PAPER_L1: f64 = -1.3058e-3;

    /// One parameter's value.
    pub fn get(&self, p: Param) -> f64 {
        let (i, d) = (&self.intrinsics, &self.distortion);
        match p {
            Param::F => i.f,
            Param::Cx => i.cx,
            Param::Cy => i.cy,
            Param::Skew => i.skew,
            Param::K1 => d.k1,
            Param::K2 => d.k2,
            Param::K3 => d.k3,
            Param::P1 => d.p1,
            Param::P2 => d.p2,
            Param::L1 => d.l1,
            Param::L2 => d.l2,
        }
    }

    /// Sets one parameter.
    pub fn set(&mut self, p: Param, value: f64) {
        let (i, d) = (&mut self.intrinsics, &mut self.distortion);
        let slot = match p {
            Param::F => &mut i.f,
            Param::Cx => &mut i.cx,
            Param::Cy => &mut i.cy,
            Param::Skew => &mut i.skew,
            Param::K1 => &mut d.k1,
            Param::K2 => &mut d.k2,
            Param::K3 => &mut d.k3,
            Param::P1 => &mut d.p1,
            Param::P2 => &mut d.p2,
            Param::L1 => &mut d.l1,
            Param::L2 => &mut d.l2,
        };
        *slot = value;
    }

    /// The parameter vector in [`Param::ALL`] order.
    pub fn to_array(&self) -> [f64; N_PARAMS] {
        Param::ALL.map(|p| self.get(p))
    }

    /// The model of a parameter vector in [`Param::ALL`] order.
    pub fn from_array(values: &[f64; N_PARAMS]) -> Self {
        let mut m = Self::pinhole(1.0, 0.0, 0.0);
        for p in Param::ALL {
            m.set(p, values[p.index()]);
        }
        m
    }

    /// Checks that every parameter is finite and `f > 0`.
    pub fn validate(&self) -> Result<(), ModelError> {
        for p in Param::ALL {
            let value = self.get(p);
            if !value.is_finite() {
                return Err(ModelError::InvalidParameter {
                    name: p.name(),
                    value,
                    reason: "must be finite",
                });
            }
        }
        if self.intrinsics.f <= 0.0 {
            return Err(ModelError::InvalidParameter {
                name: "f",
                value: self.intrinsics.f,
                reason: "the focal length must be positive",
            });
        }
        Ok(())
    }
}
