//! A realistic, non-radial non-linearity of a pin-cushion PSD (docs/model.md
//! §8.3), for simulation: where the PSD reports a spot that is really at
//! `s`,
//!
//! ```text
//! reported = s + E(s),    u = 2 s_x / Lx,  v = 2 s_y / Ly,  g(t) = (e^{4(t² − 1)} − e^{−4}) / (1 − e^{−4})
//! E_x = (Lx/2) · (−0.014 u³ − 0.008 u v² − 0.006 u g(v) + 0.004 u² v)
//! E_y = (Ly/2) · (−0.018 v³ − 0.006 v u² − 0.005 v g(u) + 0.003 u v)
//! ```
//!
//! It pulls reported points towards the centre (the pin-cushion's outer
//! zone), more along y than along x (anisotropic, as electrode geometries
//! make it), growing towards the edges and fastest near the corners (`g`
//! rises from 0 at the centre to 1 at the edge, steeply over the last
//! millimetre): on the 9 mm S5991-01 it is 63 µm at the middle of the x edges,
//! 81 µm at the middle of the y edges (≈ 1 % of the size), and 108 µm / 117
//! µm (x / y) at the corners. It is not a polynomial and not radial: neither
//! `l1` nor a low-order fit holds it exactly. Its Jacobian `I + ∂E/∂s` stays
//! within 15 % of the identity over the active area, so it is one-to-one.
//!
//! The true spot of a reported point ([`PsdNonlinearity::spot`]) is found by
//! Newton's method on the 2×2 Jacobian to 1e-13 mm; `spot(r) − r` is the
//! true field a PSD map (measured → true) estimates.

use nalgebra::{Matrix2, Vector2};
use psdcal_model::PsdGeometry;

/// The simulated non-linearity over an active area.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PsdNonlinearity {
    geometry: PsdGeometry,
}

fn edge(t: f64) -> (f64, f64) {
    let e4 = (-4.0f64).exp();
    let x = (4.0 * (t * t - 1.0)).exp();
    ((x - e4) / (1.0 - e4), 8.0 * t * x / (1.0 - e4))
}

impl PsdNonlinearity {
    /// The non-linearity of a PSD of active area `geometry`.
    pub fn new(geometry: PsdGeometry) -> Self {
        Self { geometry }
    }

    /// `E(s)` with `∂E/∂s`.
    pub fn displacement(&self, s: &Vector2<f64>) -> (Vector2<f64>, Matrix2<f64>) {
        let (hx, hy) = (0.5 * self.geometry.lx, 0.5 * self.geometry.ly);
        let (u, v) = (s.x / hx, s.y / hy);
        let (gu, dgu) = edge(u);
        let (gv, dgv) = edge(v);
        let ex = -0.014 * u.powi(3) - 0.008 * u * v * v - 0.006 * u * gv + 0.004 * u * u * v;
        let ey = -0.018 * v.powi(3) - 0.006 * v * u * u - 0.005 * v * gu + 0.003 * u * v;
        let dex_du = -0.042 * u * u - 0.008 * v * v - 0.006 * gv + 0.008 * u * v;
        let dex_dv = -0.016 * u * v - 0.006 * u * dgv + 0.004 * u * u;
        let dey_du = -0.012 * v * u - 0.005 * v * dgu + 0.003 * v;
        let dey_dv = -0.054 * v * v - 0.006 * u * u - 0.005 * gu + 0.003 * u;
        // ∂(h e)/∂s = h ∂e/∂u · (1/h_s).
        let j = Matrix2::new(dex_du, dex_dv * hx / hy, dey_du * hy / hx, dey_dv);
        (Vector2::new(hx * ex, hy * ey), j)
    }

    /// Where the PSD reports a spot at `s`.
    pub fn reported(&self, s: &Vector2<f64>) -> Vector2<f64> {
        s + self.displacement(s).0
    }

    /// The true spot of a reported point (Newton; `None` when it does not
    /// converge, far off the active area).
    pub fn spot(&self, reported: &Vector2<f64>) -> Option<Vector2<f64>> {
        let mut s = *reported;
        for _ in 0..50 {
            let (e, j) = self.displacement(&s);
            let r = s + e - reported;
            if r.norm() < 1e-13 {
                return Some(s);
            }
            let step = (Matrix2::identity() + j).try_inverse()? * r;
            s -= step;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magnitudes_and_jacobian_as_documented() {
        let nl = PsdNonlinearity::new(PsdGeometry::default());
        let e = |x: f64, y: f64| nl.displacement(&Vector2::new(x, y)).0;
        assert!((e(4.5, 0.0).x + 0.063).abs() < 1e-12);
        assert!((e(0.0, 4.5).y + 0.081).abs() < 1e-12);
        assert!((e(4.5, 4.5) - Vector2::new(-0.108, -0.117)).norm() < 1e-12);
        // ∂E/∂s against central differences.
        for p in [Vector2::new(1.3, -2.2), Vector2::new(-4.1, 3.9)] {
            let (_, j) = nl.displacement(&p);
            for k in 0..2 {
                let mut d = Vector2::zeros();
                d[k] = 1e-6;
                let fd = (nl.displacement(&(p + d)).0 - nl.displacement(&(p - d)).0) / 2e-6;
                assert!((fd - j.column(k)).norm() < 1e-9, "{fd:?} {j:?}");
            }
            let back = nl.spot(&nl.reported(&p)).unwrap();
            assert!((back - p).norm() < 1e-12);
        }
    }
}
