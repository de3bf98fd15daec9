//! The true sensor of a wide scenario: the paper's lenses
//! (`SensorModel::paper_lens1`, `paper_lens2`) with every parameter jittered,
//! and the PSD distortion `l1` of either sign or none.
//!
//! | parameter | lens 1 | lens 2 |
//! | --- | --- | --- |
//! | `f` | 25 mm × U(0.9, 1.1) | 8 mm × U(0.9, 1.1) |
//! | `cx`, `cy` | U(−0.8, 0.8) mm each | same |
//! | `k1` | 2e-3 mm⁻² × U(0.5, 1.5) | 1e-2 mm⁻² × U(0.5, 1.5) |
//! | `k2` | U(−1e-5, 1e-5) mm⁻⁴ | 3e-5 mm⁻⁴ × U(0.5, 1.5) |
//! | `l1` | 0 (half), else ±U(0.5e-3, 2.5e-3) mm⁻², either sign | same |
//!
//! Skew, `k3`, tangential terms and `l2` are zero.

use psdcal_model::SensorModel;
use rand::Rng;

/// Which of the paper's lenses a scenario is built around.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lens {
    /// f ≈ 25 mm, k1 ≈ 2e-3 mm⁻².
    One,
    /// f ≈ 8 mm, k1 ≈ 1e-2 mm⁻², k2 ≈ 3e-5 mm⁻⁴.
    Two,
}

impl Lens {
    /// 1 or 2.
    pub fn number(self) -> u8 {
        match self {
            Lens::One => 1,
            Lens::Two => 2,
        }
    }
}

/// Draws the lens and the true sensor (module documentation), in this order:
/// lens, f, cx, cy, k1, k2, whether the PSD is distorted, then (if it is)
/// |l1| and its sign.
pub fn draw_sensor<R: Rng + ?Sized>(rng: &mut R) -> (Lens, SensorModel) {
    let lens = if rng.random_bool(0.5) {
        Lens::One
    } else {
        Lens::Two
    };
    let mut m = match lens {
        Lens::One => SensorModel::paper_lens1(),
        Lens::Two => SensorModel::paper_lens2(),
    };
    m.intrinsics.f *= rng.random_range(0.9..1.1);
    m.intrinsics.cx = rng.random_range(-0.8..0.8);
    m.intrinsics.cy = rng.random_range(-0.8..0.8);
    m.distortion.k1 *= rng.random_range(0.5..1.5);
    m.distortion.k2 = match lens {
        Lens::One => rng.random_range(-1e-5..1e-5),
        Lens::Two => m.distortion.k2 * rng.random_range(0.5..1.5),
    };
    if rng.random_bool(0.5) {
        let magnitude = rng.random_range(0.5e-3..2.5e-3);
        m.distortion.l1 = if rng.random_bool(0.5) {
            magnitude
        } else {
            -magnitude
        };
    }
    (lens, m)
}
