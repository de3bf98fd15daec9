//! The PSD's own non-linearity as a map (docs/model.md §8.3): a smooth 2-D
//! displacement field from the measured point to the true spot position,
//!
//! ```text
//! out = m + Σ_k (ax_k, ay_k) φ_k(m),      k = 0 … K − 1
//! ∂out/∂m = I + Σ_k (ax_k, ay_k)ᵀ ∇φ_k(m)
//! ∂out/∂ax_k = (φ_k, 0),   ∂out/∂ay_k = (0, φ_k)
//! ```
//!
//! with the block `θ = (ax_0 … ax_{K−1}, ay_0 … ay_{K−1})` in mm, over a
//! *frame* rectangle `[x0, x1] × [y0, y1]` (the active area, or the scan's
//! bounding box) and one of two bases ([`MapBasis`]):
//!
//! - **Polynomial of order N**: `φ = P_i(u) P_j(v)` for `i + j ≤ N`, Legendre
//!   polynomials of the frame coordinates `u = (2x − x0 − x1)/(x1 − x0)`,
//!   `v` likewise (`(i + 1)P_{i+1} = (2i + 1)u P_i − i P_{i−1}`,
//!   `P'_{i+1} = P'_{i−1} + (2i + 1) P_i`); `K = (N + 1)(N + 2)/2`, ordered by
//!   degree `d = i + j`, then `i` from `d` down to 0. Legendre rather than
//!   monomials keeps the fit's normal equations well conditioned.
//! - **Cubic B-spline on a uniform grid** of `cx × cy` cells over the frame:
//!   `φ_(a,b) = B_a(s) B_b(t)`, `s = cx (x − x0)/(x1 − x0)`, with the uniform
//!   cubic B-spline pieces on span `⌊s⌋` (clamped to the grid, so the field
//!   continues as the edge polynomial just outside the frame)
//!   `B₀ = (1−τ)³/6`, `B₁ = (3τ³ − 6τ² + 4)/6`, `B₂ = (−3τ³ + 3τ² + 3τ + 1)/6`,
//!   `B₃ = τ³/6`; `K = (cx + 3)(cy + 3)`; 16 basis functions are non-zero at a
//!   point.
//!
//! Parameter names: `map_x_i_j`, `map_y_i_j` (Legendre degrees `i, j`, or
//! the control point's column `i` and row `j`), unit mm, neutral 0.
//!
//! **Domain.** A map fitted to a scan is known only where the scan was: the
//! stage carries the scan's convex hull (in measured coordinates) and a point
//! outside it is outside the model's valid region (docs/model.md §8.2).

use nalgebra::{Matrix2, Vector2};
use serde_json::{json, Value};

use crate::hull::ConvexHull;
use crate::stage::{ParameterInfo, Stage, StageJacobian};
use crate::ModelError;

/// Highest polynomial order.
pub const MAX_POLY_ORDER: usize = 12;
/// Most spline cells along an axis (23² = 529 coefficients per axis).
pub const MAX_SPLINE_CELLS: usize = 20;
/// The stage's kind in calibration.json.
pub const PSD_MAP_KIND: &str = "psd_map";

/// The family of basis functions of a map, with its size.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MapBasis {
    /// Legendre polynomials of total degree ≤ `order`.
    Polynomial {
        /// Highest total degree.
        order: usize,
    },
    /// Tensor-product uniform cubic B-spline of `cells_x × cells_y` cells.
    Spline {
        /// Cells along x.
        cells_x: usize,
        /// Cells along y.
        cells_y: usize,
    },
}

impl MapBasis {
    /// Basis functions per axis, `K`.
    pub fn terms(&self) -> usize {
        match *self {
            MapBasis::Polynomial { order } => (order + 1) * (order + 2) / 2,
            MapBasis::Spline { cells_x, cells_y } => (cells_x + 3) * (cells_y + 3),
        }
    }

    /// Refuses orders and grids out of range.
    pub fn check(&self) -> Result<(), ModelError> {
        let bad = |reason: String| Err(ModelError::InvalidModel { reason });
        match *self {
            MapBasis::Polynomial { order } if order > MAX_POLY_ORDER => bad(format!(
                "a PSD map of polynomial order {order}; expected 0 to {MAX_POLY_ORDER}"
            )),
            MapBasis::Spline { cells_x, cells_y }
                if !(1..=MAX_SPLINE_CELLS).contains(&cells_x)
                    || !(1..=MAX_SPLINE_CELLS).contains(&cells_y) =>
            {
                bad(format!(
                    "a PSD map spline of {cells_x} × {cells_y} cells; expected 1 to \
                     {MAX_SPLINE_CELLS} cells along each axis"
                ))
            }
            _ => Ok(()),
        }
    }

    /// `poly:N` or `spline:N` (`spline:NxM` when the grid is not square).
    pub fn label(&self) -> String {
        match *self {
            MapBasis::Polynomial { order } => format!("poly:{order}"),
            MapBasis::Spline { cells_x, cells_y } if cells_x == cells_y => {
                format!("spline:{cells_x}")
            }
            MapBasis::Spline { cells_x, cells_y } => format!("spline:{cells_x}x{cells_y}"),
        }
    }

    /// Parses [`Self::label`]'s text.
    pub fn parse(text: &str) -> Option<Self> {
        let (family, size) = text.trim().split_once(':')?;
        let number = |s: &str| s.trim().parse::<usize>().ok();
        let basis = match family.trim() {
            "poly" => MapBasis::Polynomial {
                order: number(size)?,
            },
            "spline" => {
                let (a, b) = size.split_once('x').unwrap_or((size, size));
                MapBasis::Spline {
                    cells_x: number(a)?,
                    cells_y: number(b)?,
                }
            }
            _ => return None,
        };
        basis.check().ok().map(|_| basis)
    }

    /// The `(i, j)` indices of each basis function, in block order.
    pub fn indices(&self) -> Vec<(usize, usize)> {
        match *self {
            MapBasis::Polynomial { order } => (0..=order)
                .flat_map(|d| (0..=d).rev().map(move |i| (i, d - i)))
                .collect(),
            MapBasis::Spline { cells_x, cells_y } => (0..cells_x + 3)
                .flat_map(|i| (0..cells_y + 3).map(move |j| (i, j)))
                .collect(),
        }
    }
}

/// The rectangle a map's coordinates are normalised over, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapFrame {
    /// Lower-left corner `(x0, y0)`.
    pub min: Vector2<f64>,
    /// Upper-right corner `(x1, y1)`.
    pub max: Vector2<f64>,
}

impl MapFrame {
    /// The active area `[−Lx/2, Lx/2] × [−Ly/2, Ly/2]`.
    pub fn centred(lx: f64, ly: f64) -> Self {
        Self {
            min: Vector2::new(-0.5 * lx, -0.5 * ly),
            max: Vector2::new(0.5 * lx, 0.5 * ly),
        }
    }

    fn check(&self) -> Result<(), ModelError> {
        let ok = self
            .min
            .iter()
            .chain(self.max.iter())
            .all(|v| v.is_finite())
            && self.max.x > self.min.x
            && self.max.y > self.min.y;
        if ok {
            Ok(())
        } else {
            Err(ModelError::InvalidModel {
                reason: format!(
                    "a PSD map's frame [{}, {}] × [{}, {}] mm is empty or not finite",
                    self.min.x, self.max.x, self.min.y, self.max.y
                ),
            })
        }
    }
}

/// The PSD-map stage: basis, frame, domain and the named block.
#[derive(Debug, Clone)]
pub struct PsdMap {
    basis: MapBasis,
    frame: MapFrame,
    hull: Option<ConvexHull>,
    parameters: Vec<ParameterInfo>,
}

/// Legendre polynomials `P_0 … P_n` and their derivatives at `u`.
#[inline]
fn legendre(u: f64, n: usize, p: &mut [f64], d: &mut [f64]) {
    p[0] = 1.0;
    d[0] = 0.0;
    if n >= 1 {
        p[1] = u;
        d[1] = 1.0;
    }
    for i in 1..n {
        let fi = i as f64;
        p[i + 1] = ((2.0 * fi + 1.0) * u * p[i] - fi * p[i - 1]) / (fi + 1.0);
        d[i + 1] = d[i - 1] + (2.0 * fi + 1.0) * p[i];
    }
}

/// The span of a uniform cubic B-spline with `cells` cells at cell
/// coordinate `s`, and the four non-zero basis values and derivatives
/// (with respect to `s`).
#[inline]
fn spline_span(s: f64, cells: usize) -> (usize, [f64; 4], [f64; 4]) {
    let span = if s.is_finite() {
        (s.floor().max(0.0) as usize).min(cells - 1)
    } else {
        0
    };
    let t = s - span as f64;
    let (t2, t3) = (t * t, t * t * t);
    let w = 1.0 - t;
    let b = [
        w * w * w / 6.0,
        (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
        (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
        t3 / 6.0,
    ];
    let db = [
        -0.5 * w * w,
        (3.0 * t2 - 4.0 * t) / 2.0,
        (-3.0 * t2 + 2.0 * t + 1.0) / 2.0,
        0.5 * t2,
    ];
    (span, b, db)
}

impl PsdMap {
    /// A map of `basis` over `frame`, defined on `hull` (`None`: everywhere).
    pub fn new(
        basis: MapBasis,
        frame: MapFrame,
        hull: Option<ConvexHull>,
    ) -> Result<Self, ModelError> {
        basis.check()?;
        frame.check()?;
        let mut parameters = Vec::with_capacity(2 * basis.terms());
        for axis in ["x", "y"] {
            for (i, j) in basis.indices() {
                parameters.push(ParameterInfo::new(
                    format!("map_{axis}_{i}_{j}"),
                    "mm",
                    0.0,
                    1e-3,
                ));
            }
        }
        Ok(Self {
            basis,
            frame,
            hull,
            parameters,
        })
    }

    /// The basis.
    pub fn basis(&self) -> MapBasis {
        self.basis
    }

    /// The frame.
    pub fn frame(&self) -> MapFrame {
        self.frame
    }

    /// The domain (the scan's hull), when limited.
    pub fn hull(&self) -> Option<&ConvexHull> {
        self.hull.as_ref()
    }

    /// Basis functions per axis, `K` (the block has `2K` parameters).
    pub fn terms(&self) -> usize {
        self.basis.terms()
    }

    /// Calls `f(k, φ_k, ∂φ_k/∂x, ∂φ_k/∂y)` for every basis function that may
    /// be non-zero at `p` (all of them for a polynomial, 16 for a spline).
    #[inline]
    pub fn for_each_term(&self, p: &Vector2<f64>, mut f: impl FnMut(usize, f64, f64, f64)) {
        let size = self.frame.max - self.frame.min;
        match self.basis {
            MapBasis::Polynomial { order } => {
                let sx = 2.0 / size.x;
                let sy = 2.0 / size.y;
                let u = (p.x - self.frame.min.x) * sx - 1.0;
                let v = (p.y - self.frame.min.y) * sy - 1.0;
                let mut pu = [0.0; MAX_POLY_ORDER + 1];
                let mut du = [0.0; MAX_POLY_ORDER + 1];
                let mut pv = [0.0; MAX_POLY_ORDER + 1];
                let mut dv = [0.0; MAX_POLY_ORDER + 1];
                legendre(u, order, &mut pu, &mut du);
                legendre(v, order, &mut pv, &mut dv);
                let mut k = 0;
                for d in 0..=order {
                    for i in (0..=d).rev() {
                        let j = d - i;
                        f(k, pu[i] * pv[j], du[i] * sx * pv[j], pu[i] * dv[j] * sy);
                        k += 1;
                    }
                }
            }
            MapBasis::Spline { cells_x, cells_y } => {
                let sx = cells_x as f64 / size.x;
                let sy = cells_y as f64 / size.y;
                let (ix, bx, dbx) = spline_span((p.x - self.frame.min.x) * sx, cells_x);
                let (iy, by, dby) = spline_span((p.y - self.frame.min.y) * sy, cells_y);
                let rows = cells_y + 3;
                for a in 0..4 {
                    for b in 0..4 {
                        let k = (ix + a) * rows + iy + b;
                        f(k, bx[a] * by[b], dbx[a] * sx * by[b], bx[a] * dby[b] * sy);
                    }
                }
            }
        }
    }

    /// The displacement `out − m` at `m`.
    pub fn displacement(&self, params: &[f64], m: &Vector2<f64>) -> Vector2<f64> {
        let k_axis = self.terms();
        let mut d = Vector2::zeros();
        self.for_each_term(m, |k, phi, _, _| {
            d.x += params[k] * phi;
            d.y += params[k_axis + k] * phi;
        });
        d
    }

    /// The stage's structure as calibration.json writes it (see
    /// [`Stage::configuration`]).
    fn configuration_json(&self) -> Value {
        let basis = match self.basis {
            MapBasis::Polynomial { order } => json!({"basis": "polynomial", "order": order}),
            MapBasis::Spline { cells_x, cells_y } => {
                json!({"basis": "spline", "cells": [cells_x, cells_y]})
            }
        };
        let mut v = basis;
        v["frame_mm"] = json!([
            self.frame.min.x,
            self.frame.min.y,
            self.frame.max.x,
            self.frame.max.y
        ]);
        v["hull_mm"] = match &self.hull {
            Some(h) => Value::Array(h.vertices().iter().map(|p| json!([p.x, p.y])).collect()),
            None => Value::Null,
        };
        v
    }

    /// The stage from [`Stage::configuration`]'s JSON.
    pub fn from_configuration(v: &Value) -> Result<Self, ModelError> {
        let bad = |what: &str| ModelError::InvalidModel {
            reason: format!("a psd_map stage's configuration: {what}"),
        };
        let size = |key: &str| -> Result<usize, ModelError> {
            v.get(key)
                .and_then(Value::as_u64)
                .map(|n| n as usize)
                .ok_or_else(|| bad(&format!("'{key}' must be a whole number")))
        };
        let basis = match v.get("basis").and_then(Value::as_str) {
            Some("polynomial") => MapBasis::Polynomial {
                order: size("order")?,
            },
            Some("spline") => {
                let cells = v
                    .get("cells")
                    .and_then(Value::as_array)
                    .filter(|a| a.len() == 2)
                    .and_then(|a| Some((a[0].as_u64()?, a[1].as_u64()?)))
                    .ok_or_else(|| bad("'cells' must be two whole numbers"))?;
                MapBasis::Spline {
                    cells_x: cells.0.min(usize::MAX as u64) as usize,
                    cells_y: cells.1.min(usize::MAX as u64) as usize,
                }
            }
            _ => return Err(bad("'basis' must be \"polynomial\" or \"spline\"")),
        };
        let numbers =
            |x: &Value| -> Option<Vec<f64>> { x.as_array()?.iter().map(Value::as_f64).collect() };
        let frame = v
            .get("frame_mm")
            .and_then(numbers)
            .filter(|f| f.len() == 4)
            .ok_or_else(|| bad("'frame_mm' must be [x0, y0, x1, y1]"))?;
        let frame = MapFrame {
            min: Vector2::new(frame[0], frame[1]),
            max: Vector2::new(frame[2], frame[3]),
        };
        let hull = match v.get("hull_mm") {
            None | Some(Value::Null) => None,
            Some(h) => {
                let vertices = h
                    .as_array()
                    .and_then(|a| {
                        a.iter()
                            .map(|p| numbers(p).filter(|p| p.len() == 2))
                            .map(|p| p.map(|p| Vector2::new(p[0], p[1])))
                            .collect::<Option<Vec<_>>>()
                    })
                    .ok_or_else(|| bad("'hull_mm' must be a list of [x, y]"))?;
                Some(ConvexHull::from_vertices(vertices)?)
            }
        };
        Self::new(basis, frame, hull)
    }
}

impl Stage for PsdMap {
    fn kind(&self) -> &str {
        PSD_MAP_KIND
    }

    fn parameters(&self) -> &[ParameterInfo] {
        &self.parameters
    }

    fn apply(
        &self,
        params: &[f64],
        input: &Vector2<f64>,
        jacobian: Option<StageJacobian<'_>>,
    ) -> Vector2<f64> {
        let k_axis = self.terms();
        let mut out = *input;
        let mut d = Matrix2::identity();
        match jacobian {
            None => self.for_each_term(input, |k, phi, _, _| {
                out.x += params[k] * phi;
                out.y += params[k_axis + k] * phi;
            }),
            Some(j) => {
                j.wrt_params.iter_mut().for_each(|v| *v = 0.0);
                self.for_each_term(input, |k, phi, gx, gy| {
                    let (ax, ay) = (params[k], params[k_axis + k]);
                    out.x += ax * phi;
                    out.y += ay * phi;
                    d[(0, 0)] += ax * gx;
                    d[(0, 1)] += ax * gy;
                    d[(1, 0)] += ay * gx;
                    d[(1, 1)] += ay * gy;
                    j.wrt_params[2 * k] = phi;
                    j.wrt_params[2 * (k_axis + k) + 1] = phi;
                });
                *j.wrt_input = d;
            }
        }
        out
    }

    fn contains_input(&self, input: &Vector2<f64>) -> bool {
        self.hull.as_ref().is_none_or(|h| h.contains(input))
    }

    fn has_domain(&self) -> bool {
        self.hull.is_some()
    }

    fn domain(&self) -> Option<&ConvexHull> {
        self.hull.as_ref()
    }

    fn example_parameters(&self) -> Vec<Vec<f64>> {
        let k_axis = self.terms();
        let indices = self.basis.indices();
        let field = |seed: f64| -> Vec<f64> {
            (0..2 * k_axis)
                .map(|k| {
                    let (i, j) = indices[k % k_axis];
                    match self.basis {
                        // A few tens of µm, decaying with the degree.
                        MapBasis::Polynomial { .. } => {
                            0.02 * (seed * (k as f64 + 1.0)).sin() / (1.0 + (i + j) as f64).powi(2)
                        }
                        // Control values of a smooth field of ±30 µm.
                        MapBasis::Spline { .. } => {
                            let axis = (k / k_axis) as f64;
                            0.03 * (seed + 0.9 * i as f64 + axis).sin() * (0.6 * j as f64).cos()
                        }
                    }
                })
                .collect()
        };
        vec![vec![0.0; 2 * k_axis], field(0.7), field(1.9)]
    }

    fn configuration(&self) -> Value {
        self.configuration_json()
    }

    fn clone_box(&self) -> Box<dyn Stage> {
        Box::new(self.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legendre_matches_closed_forms() {
        let (mut p, mut d) = ([0.0; 5], [0.0; 5]);
        let u: f64 = 0.37;
        legendre(u, 4, &mut p, &mut d);
        assert!((p[2] - 0.5 * (3.0 * u * u - 1.0)).abs() < 1e-15);
        assert!((p[3] - 0.5 * (5.0 * u.powi(3) - 3.0 * u)).abs() < 1e-15);
        assert!((d[3] - 0.5 * (15.0 * u * u - 3.0)).abs() < 1e-14);
        assert!((p[4] - (35.0 * u.powi(4) - 30.0 * u * u + 3.0) / 8.0).abs() < 1e-15);
    }

    #[test]
    fn splines_partition_unity_and_reproduce_a_plane() {
        let map = PsdMap::new(
            MapBasis::Spline {
                cells_x: 4,
                cells_y: 3,
            },
            MapFrame::centred(9.0, 9.0),
            None,
        )
        .unwrap();
        // Control values of the plane x + 2y at the Greville abscissae
        // (knot i − 1 for a uniform cubic): the spline reproduces it exactly.
        let k_axis = map.terms();
        let mut params = vec![0.0; 2 * k_axis];
        for (k, (i, j)) in map.basis().indices().into_iter().enumerate() {
            let x = -4.5 + 9.0 / 4.0 * (i as f64 - 1.0);
            let y = -4.5 + 9.0 / 3.0 * (j as f64 - 1.0);
            params[k] = 1e-3 * (x + 2.0 * y);
            params[k_axis + k] = 1e-3;
        }
        for p in [
            Vector2::new(0.1, -3.0),
            Vector2::new(4.4, 4.5),
            Vector2::new(-4.6, 0.0),
        ] {
            let mut sum = 0.0;
            map.for_each_term(&p, |_, phi, _, _| sum += phi);
            assert!((sum - 1.0).abs() < 1e-14);
            let d = map.displacement(&params, &p);
            assert!((d.x - 1e-3 * (p.x + 2.0 * p.y)).abs() < 1e-15, "{d:?}");
            assert!((d.y - 1e-3).abs() < 1e-15);
        }
    }

    #[test]
    fn the_hull_limits_the_domain_and_configuration_round_trips() {
        let square: Vec<_> = [(-3.0, -3.0), (3.0, -3.0), (3.0, 3.0), (-3.0, 3.0)]
            .iter()
            .map(|(x, y)| Vector2::new(*x, *y))
            .collect();
        let hull = ConvexHull::of_points(&square).unwrap();
        let map = PsdMap::new(
            MapBasis::Polynomial { order: 3 },
            MapFrame::centred(9.0, 9.0),
            Some(hull),
        )
        .unwrap();
        assert!(map.contains_input(&Vector2::new(2.9, -2.9)));
        assert!(!map.contains_input(&Vector2::new(3.1, 0.0)));
        let back = PsdMap::from_configuration(&map.configuration()).unwrap();
        assert_eq!(back.basis(), map.basis());
        assert_eq!(back.frame(), map.frame());
        assert_eq!(back.hull(), map.hull());
        assert!(PsdMap::from_configuration(&json!({"basis": "cubic"})).is_err());
        assert_eq!(
            MapBasis::parse("spline:8"),
            Some(MapBasis::Spline {
                cells_x: 8,
                cells_y: 8
            })
        );
        assert_eq!(MapBasis::parse("poly:3").map(|b| b.terms()), Some(10));
        assert_eq!(MapBasis::parse("poly:99"), None);
    }
}
