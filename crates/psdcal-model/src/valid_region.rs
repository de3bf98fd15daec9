//! The model's valid region (docs/model.md §8.2): where the measured → ideal
//! map (the correction, every distortion stage of a [`Model`]) is one-to-one.
//!
//! The correction `x = u(m)` folds where the determinant of its 2×2
//! Jacobian `J(m) = ∂ideal/∂measured` stops being positive. Past the first
//! fold along a ray, a measured point has a twin on the near side of the fold
//! with the same (or a mirrored) ideal point, and nothing tells which one the
//! light came from: such a point has no answer. The region is star-shaped
//! about the optical centre `c = (cx, cy)`:
//!
//! ```text
//! u_i   = (cos θ_i, sin θ_i),      θ_i = 2π i / N,   i = 0 … N − 1   (N = 90, REGION_RAYS)
//! R_i   = the distance from c along u_i to the edge of the checked zone,
//!         the active area scaled by ZONE_SCALE = 1.5 about the electrical centre
//! r_i   = sup { t ≤ R_i : det J(c + s u_i) > 1e-12 for every s ∈ [0, t] }
//! ```
//!
//! When the model's measured points must also lie in a stage's own domain
//! (a PSD map is known only on its scan's convex hull, docs/model.md §8.3),
//! that domain `H` bounds the rays too, `R_i ← min(R_i, h_i)` with `h_i` the
//! exact distance from `c` along `u_i` to the hull's edge, and every ray
//! records how it ends: at a fold, at the domain's edge, or at the checked
//! zone's edge. A domain that is not a polygon in measured coordinates (a
//! later stage's) counts as `det J ≤ 0` outside it, so the bisection finds
//! its edge, which is then reported as a fold.
//!
//! `r_i` is found by stepping along the ray from `c` and bisecting the first
//! step whose end is not positive (or not finite) to 1e-12 relative; the
//! stored radius is the bracket's positive end, so it lies before the fold.
//! The steps adapt to the determinant: at most `R_i / 24`; where `det J`
//! falls, half the distance at which the secant through the last two samples
//! reaches zero, but not under `R_i / 1024`. A dip of the determinant toward
//! zero is thus sampled densely, and a correction that stays far from
//! folding costs 24 evaluations a ray. A ray that does not fold before the
//! zone's edge has `r_i = R_i`. A model whose correction is not positive at
//! the centre itself has an empty region (every `r_i = 0`).
//!
//! A point `p` at distance `ρ = |p − c|` in direction `θ ∈ [θ_i, θ_{i+1})` is
//! inside when it is in the domain `H` (exactly: [`ConvexHull::contains`])
//! and
//!
//! ```text
//! ρ < min(r'_i, r'_{i+1}) · (1 − 1e-3),   r'_k = ∞ when ray k ends at H's edge, else r_k
//! ```
//!
//! the smaller neighbouring radius with a relative margin of 1e-3, so that
//! between rays (4° apart) the rule stays on the safe side of a smooth
//! boundary. A ray that ends at the domain's edge sets no radial limit: the
//! domain itself is checked exactly, so a point inside a polygonal hull is
//! never cut off by the chord between two rays (which would shave up to a
//! few tenths of a millimetre off a hull's corners), and the hull's edge is
//! never called a fold. `whole_active_area` is true when every point of the active area
//! is inside by this rule (checked exactly: on each interval between rays the
//! largest distance from `c` to the active area's far edge is reached at the
//! interval's ends or at a corner direction).

use std::f64::consts::TAU;

use nalgebra::Vector2;

use crate::hull::ConvexHull;
use crate::model::Model;
use crate::params::SensorModel;
use crate::psd::PsdGeometry;
use crate::ModelError;

/// Rays of a region computed by [`ValidRegion::of_model`].
pub const REGION_RAYS: usize = 90;
/// Fewest rays a region may have (a region read from a file).
pub const MIN_REGION_RAYS: usize = 8;
/// The checked zone: the active area scaled by this factor about the
/// electrical centre (points a little off the active area are still
/// answered, with a caution).
pub const ZONE_SCALE: f64 = 1.5;
/// Fewest steps along a ray (the longest step is `reach` over this).
pub const MAX_STEPS_PER_RAY: usize = 24;
/// The shortest step is `reach` over this.
pub const MIN_STEP_FRACTION: usize = 1024;
/// Smallest determinant of `∂ideal/∂measured` that counts as positive (the
/// threshold of the inverse distortion, docs/model.md §2.5).
pub const MIN_FOLD_DET: f64 = 1e-12;
/// Relative margin of the inside rule.
pub const REGION_MARGIN: f64 = 1e-3;

/// Where the measured → ideal map is one-to-one: a radius per ray direction
/// from the optical centre, within the model's domain.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidRegion {
    centre: Vector2<f64>,
    radius: Vec<f64>,
    ends: Vec<RegionEnd>,
    geometry: PsdGeometry,
    domain: Option<ConvexHull>,
    whole_active_area: bool,
}

/// How a ray of the region ends, or why a point is outside.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum RegionEnd {
    /// The correction folds over (its Jacobian's determinant reaches 0).
    Fold,
    /// The model's domain ends: a PSD map's scan hull.
    DomainEdge,
    /// The edge of the checked zone, far off the active area.
    ZoneEdge,
}

/// Why a point is outside a region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutsideRegion {
    /// Distance of the point from the region's centre, mm.
    pub distance_mm: f64,
    /// How far the region reaches in the point's direction (after the
    /// margin; for [`RegionEnd::DomainEdge`], the domain's edge), mm.
    pub limit_mm: f64,
    /// Where the region ends there.
    pub end: RegionEnd,
}

impl OutsideRegion {
    /// Whether the region ends there at a fold.
    pub fn fold(&self) -> bool {
        self.end == RegionEnd::Fold
    }
}

impl ValidRegion {
    /// The region of `model`'s distortion stages over `geometry`'s active
    /// area, centred on the model's optical centre `(cx, cy)` (0 when the
    /// chain has none), with [`REGION_RAYS`] rays.
    pub fn of_model(model: &Model, geometry: &PsdGeometry) -> Self {
        let centre = Vector2::new(
            model.get("cx").unwrap_or(0.0),
            model.get("cy").unwrap_or(0.0),
        );
        let usable = centre.iter().all(|v| v.is_finite())
            && geometry.lx.is_finite()
            && geometry.ly.is_finite()
            && geometry.lx > 0.0
            && geometry.ly > 0.0;
        let domain = model.measured_domain().cloned();
        if !usable {
            return Self::assemble(Vector2::zeros(), vec![0.0; REGION_RAYS], *geometry, domain);
        }
        let mut scratch = Vec::new();
        // Outside a domain that is not a polygon here (a later stage's)
        // counts as a fold: the bisection then finds that domain's edge.
        let mut det = |p: &Vector2<f64>| {
            if model.in_domain(p) {
                model.point_jacobian_with(p, &mut scratch).determinant()
            } else {
                f64::NEG_INFINITY
            }
        };
        let identity = model.distortion_is_identity() && !model.has_domain();
        let centre_ok = positive(det(&centre));
        let radius = (0..REGION_RAYS)
            .map(|i| {
                let u = direction(i, REGION_RAYS);
                let reach = ray_reach(&centre, &u, geometry, domain.as_ref());
                if identity {
                    reach
                } else if !centre_ok {
                    0.0
                } else {
                    first_fold(&mut det, &centre, &u, reach)
                }
            })
            .collect();
        Self::assemble(centre, radius, *geometry, domain)
    }

    /// The region of a standard model ([`Model::standard`]).
    pub fn of_sensor_model(model: &SensorModel, geometry: &PsdGeometry) -> Self {
        Self::of_model(&Model::standard(model), geometry)
    }

    /// A region from stored radii (ray `i` at `θ_i = 2π i / N`, `N =
    /// radius.len()`); refused when the centre or a radius is not finite, a
    /// radius is negative or beyond the checked zone, or there are fewer
    /// than [`MIN_REGION_RAYS`] rays.
    pub fn from_radii(
        centre: Vector2<f64>,
        radius: Vec<f64>,
        geometry: &PsdGeometry,
    ) -> Result<Self, ModelError> {
        let invalid = |reason: String| Err(ModelError::InvalidModel { reason });
        if radius.len() < MIN_REGION_RAYS {
            return invalid(format!(
                "a valid region of {} rays; expected at least {MIN_REGION_RAYS}",
                radius.len()
            ));
        }
        if !centre.iter().all(|v| v.is_finite()) {
            return invalid("the valid region's centre is not finite".into());
        }
        let n = radius.len();
        for (i, r) in radius.iter().enumerate() {
            let reach = zone_reach(&centre, &direction(i, n), geometry);
            if !(r.is_finite() && *r >= 0.0 && *r <= reach * (1.0 + 1e-9)) {
                return invalid(format!(
                    "the valid region's radius {r} mm of ray {i}; expected 0 to {reach} mm (the \
                     edge of the checked zone, {ZONE_SCALE} times the active area)"
                ));
            }
        }
        Ok(Self::assemble(centre, radius, *geometry, None))
    }

    /// The same region within `domain` (a stored region, whose rays do not
    /// say how they end, given its model's [`Model::measured_domain`]): a
    /// ray that ends on the domain's edge (to 1e-9 relative) ends there, not
    /// at a fold, and points outside the domain are outside.
    pub fn with_domain(self, domain: Option<ConvexHull>) -> Self {
        Self::assemble(self.centre, self.radius, self.geometry, domain)
    }

    fn assemble(
        centre: Vector2<f64>,
        radius: Vec<f64>,
        geometry: PsdGeometry,
        domain: Option<ConvexHull>,
    ) -> Self {
        let n = radius.len();
        let ends = (0..n)
            .map(|i| {
                let u = direction(i, n);
                let zone = zone_reach(&centre, &u, &geometry);
                let edge = domain.as_ref().map(|h| h.exit_distance(&centre, &u));
                let on = |reach: f64| radius[i] >= reach * (1.0 - 1e-9);
                match edge {
                    Some(h) if h < zone && on(h) => RegionEnd::DomainEdge,
                    _ if on(zone) => RegionEnd::ZoneEdge,
                    _ => RegionEnd::Fold,
                }
            })
            .collect();
        let mut region = Self {
            centre,
            radius,
            ends,
            geometry,
            domain,
            whole_active_area: false,
        };
        region.whole_active_area = region.covers_active_area();
        region
    }

    /// The centre the rays start from (the optical centre), mm.
    pub fn centre(&self) -> Vector2<f64> {
        self.centre
    }

    /// The radius of each ray, mm (ray `i` at `θ_i = 2π i / N`).
    pub fn radii(&self) -> &[f64] {
        &self.radius
    }

    /// Number of rays.
    pub fn rays(&self) -> usize {
        self.radius.len()
    }

    /// The active area the region was computed over.
    pub fn geometry(&self) -> PsdGeometry {
        self.geometry
    }

    /// The model's domain the region lies in (a PSD map's scan hull), when
    /// limited.
    pub fn domain(&self) -> Option<&ConvexHull> {
        self.domain.as_ref()
    }

    /// How each ray ends.
    pub fn ends(&self) -> &[RegionEnd] {
        &self.ends
    }

    /// Whether every point of the active area is inside.
    pub fn whole_active_area(&self) -> bool {
        self.whole_active_area
    }

    /// Whether ray `i` ends at a fold (rather than at the domain's or the
    /// zone's edge).
    pub fn folds_on_ray(&self, i: usize) -> bool {
        self.ends[i % self.rays()] == RegionEnd::Fold
    }

    /// The smallest fold radius, mm (`None` when no ray folds).
    pub fn nearest_fold_mm(&self) -> Option<f64> {
        (0..self.rays())
            .filter(|&i| self.folds_on_ray(i))
            .map(|i| self.radius[i])
            .reduce(f64::min)
    }

    /// The end point of each ray, `c + r_i u_i`, mm: the region's boundary
    /// as a closed polygon (for plots).
    pub fn boundary(&self) -> Vec<Vector2<f64>> {
        let n = self.rays();
        (0..n)
            .map(|i| self.centre + direction(i, n) * self.radius[i])
            .collect()
    }

    /// Whether `point` is inside (see the module documentation).
    pub fn contains(&self, point: &Vector2<f64>) -> bool {
        self.check(point).is_ok()
    }

    /// `Ok` when `point` is inside; otherwise how far it is and how far the
    /// region reaches in its direction.
    pub fn check(&self, point: &Vector2<f64>) -> Result<(), OutsideRegion> {
        let d = point - self.centre;
        let distance_mm = d.norm();
        if let Some(domain) = self.domain.as_ref().filter(|h| !h.contains(point)) {
            let limit_mm = if distance_mm > 0.0 {
                domain.exit_distance(&self.centre, &(d / distance_mm))
            } else {
                0.0
            };
            return Err(OutsideRegion {
                distance_mm,
                limit_mm,
                end: RegionEnd::DomainEdge,
            });
        }
        let n = self.rays();
        let theta = d.y.atan2(d.x).rem_euclid(TAU);
        let i = if theta.is_finite() {
            ((theta / TAU * n as f64).floor() as usize).min(n - 1)
        } else {
            0
        };
        let (limit_mm, ray) = self.sector_limit(i);
        if distance_mm < limit_mm {
            Ok(())
        } else {
            Err(OutsideRegion {
                distance_mm,
                limit_mm,
                end: self.ends[ray],
            })
        }
    }

    /// The radial limit between rays `i` and `i + 1` (after the margin; ∞
    /// when both end at the domain's edge) and the ray that sets it.
    fn sector_limit(&self, i: usize) -> (f64, usize) {
        let j = (i + 1) % self.rays();
        let bound = |k: usize| match self.ends[k] {
            RegionEnd::DomainEdge => f64::INFINITY,
            _ => self.radius[k],
        };
        let ray = if bound(i) <= bound(j) { i } else { j };
        (bound(ray) * (1.0 - REGION_MARGIN), ray)
    }

    /// Whether every point of the active area passes [`Self::check`].
    fn covers_active_area(&self) -> bool {
        let n = self.rays();
        let (hx, hy) = (0.5 * self.geometry.lx, 0.5 * self.geometry.ly);
        let corners: Vec<f64> = [(hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)]
            .iter()
            .map(|(x, y)| (y - self.centre.y).atan2(x - self.centre.x).rem_euclid(TAU))
            .collect();
        let far = |theta: f64| {
            let u = Vector2::new(theta.cos(), theta.sin());
            box_exit(&self.centre, &u, hx, hy)
        };
        let in_domain = self.domain.as_ref().is_none_or(|h| {
            [(hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)]
                .iter()
                .all(|&(x, y)| h.contains(&Vector2::new(x, y)))
        });
        in_domain
            && (0..n).all(|i| {
                let (a, b) = (TAU * i as f64 / n as f64, TAU * (i + 1) as f64 / n as f64);
                let limit = self.sector_limit(i).0;
                let mut worst = far(a).max(far(b));
                for &c in &corners {
                    if c >= a && c <= b {
                        worst = worst.max(far(c));
                    }
                }
                worst < limit
            })
    }
}

fn positive(det: f64) -> bool {
    det > MIN_FOLD_DET
}

/// `u_i` of `n` rays.
fn direction(i: usize, n: usize) -> Vector2<f64> {
    let theta = TAU * i as f64 / n as f64;
    Vector2::new(theta.cos(), theta.sin())
}

/// The distance from `c` along `u` to where the ray last leaves the box
/// `[−hx, hx] × [−hy, hy]` (0 when it never meets it).
fn box_exit(c: &Vector2<f64>, u: &Vector2<f64>, hx: f64, hy: f64) -> f64 {
    let mut near = 0.0f64;
    let mut far = f64::INFINITY;
    for (ci, ui, h) in [(c.x, u.x, hx), (c.y, u.y, hy)] {
        if ui.abs() < 1e-15 {
            if ci.abs() > h {
                return 0.0;
            }
        } else {
            let (t1, t2) = ((-h - ci) / ui, (h - ci) / ui);
            near = near.max(t1.min(t2));
            far = far.min(t1.max(t2));
        }
    }
    if far.is_finite() && far >= near {
        far
    } else {
        0.0
    }
}

/// How far a ray may run: to the checked zone's edge, or the domain's when
/// nearer.
fn ray_reach(
    c: &Vector2<f64>,
    u: &Vector2<f64>,
    geometry: &PsdGeometry,
    domain: Option<&ConvexHull>,
) -> f64 {
    let zone = zone_reach(c, u, geometry);
    domain.map_or(zone, |h| h.exit_distance(c, u).min(zone))
}

/// How far the checked zone reaches from `c` along `u`.
fn zone_reach(c: &Vector2<f64>, u: &Vector2<f64>, geometry: &PsdGeometry) -> f64 {
    let s = 0.5 * ZONE_SCALE;
    box_exit(c, u, s * geometry.lx, s * geometry.ly)
}

/// The last distance before the first fold along `c + t u`, `t ∈ [0, reach]`
/// (`reach` when the determinant stays positive). Adaptive steps (module
/// documentation): at most `reach / MAX_STEPS_PER_RAY`, at least
/// `reach / MIN_STEP_FRACTION`, and where the determinant falls, half the
/// distance at which the last secant would reach zero.
fn first_fold(
    det: &mut dyn FnMut(&Vector2<f64>) -> f64,
    c: &Vector2<f64>,
    u: &Vector2<f64>,
    reach: f64,
) -> f64 {
    let at = |t: f64| c + u * t;
    let h_max = reach / MAX_STEPS_PER_RAY as f64;
    let h_min = reach / MIN_STEP_FRACTION as f64;
    let (mut previous, mut d_previous) = (0.0, det(c));
    let mut h = h_max;
    while previous < reach {
        let t = (previous + h).min(reach);
        let d = det(&at(t));
        if !positive(d) {
            let (mut good, mut bad) = (previous, t);
            while bad - good > 1e-12 * bad.max(1.0) {
                let mid = 0.5 * (good + bad);
                if positive(det(&at(mid))) {
                    good = mid;
                } else {
                    bad = mid;
                }
            }
            return good;
        }
        let slope = (d - d_previous) / (t - previous);
        h = if slope < 0.0 {
            (0.5 * (d - MIN_FOLD_DET) / -slope).clamp(h_min, h_max)
        } else {
            h_max
        };
        (previous, d_previous) = (t, d);
    }
    reach
}
