//! The valid region (docs/model.md §8.2) against closed forms and a
//! brute-force scan of the Jacobian determinant.

use nalgebra::Vector2;
use psdcal_model::valid_region::{REGION_MARGIN, REGION_RAYS, ZONE_SCALE};
use psdcal_model::{Model, PsdGeometry, SensorModel, ValidRegion};

/// A lens with only radial terms about (0.5, −0.7).
fn radial(k1: f64, k2: f64) -> SensorModel {
    let mut m = SensorModel::pinhole(8.0, 0.5, -0.7);
    m.distortion.k1 = k1;
    m.distortion.k2 = k2;
    m
}

/// Smallest positive root of `1 + a s + b s²` (s = r²), if any.
fn smallest_positive_root(a: f64, b: f64) -> Option<f64> {
    let roots: Vec<f64> = if b == 0.0 {
        vec![-1.0 / a]
    } else {
        let disc = a * a - 4.0 * b;
        if disc < 0.0 {
            vec![]
        } else {
            vec![
                (-a - disc.sqrt()) / (2.0 * b),
                (-a + disc.sqrt()) / (2.0 * b),
            ]
        }
    };
    roots.into_iter().filter(|s| *s > 0.0).reduce(f64::min)
}

/// The fold radius of a radial lens, derived by hand: along a ray from the
/// centre the correction is `r ↦ R(r) = r (1 + k1 r² + k2 r⁴)`, a radial map
/// whose Jacobian determinant is `R'(r) · R(r) / r =
/// (1 + 3 k1 r² + 5 k2 r⁴)(1 + k1 r² + k2 r⁴)`: the first fold is the
/// smallest positive root of either factor.
fn fold_radius(k1: f64, k2: f64) -> f64 {
    let s = [
        smallest_positive_root(3.0 * k1, 5.0 * k2),
        smallest_positive_root(k1, k2),
    ]
    .into_iter()
    .flatten()
    .reduce(f64::min)
    .unwrap();
    s.sqrt()
}

#[test]
fn radial_fold_matches_the_closed_form() {
    let geometry = PsdGeometry::default();
    for (k1, k2) in [(-0.02, 0.0), (-0.01, -2e-4), (0.004, -3e-4)] {
        let r_star = fold_radius(k1, k2);
        // Every ray of the zone (±6.75 mm about (0, 0)) reaches past r*
        // from (0.5, −0.7): its nearest edge is 6.05 mm away.
        assert!(r_star < 6.05, "{r_star}");
        let region = ValidRegion::of_sensor_model(&radial(k1, k2), &geometry);
        assert_eq!(region.rays(), REGION_RAYS);
        assert_eq!(region.centre(), Vector2::new(0.5, -0.7));
        // Bisection to 1e-12 relative; the stored radius is before the
        // fold, where det > 1e-12, i.e. within 1e-12 / |det'(r*)| (< 1e-10
        // mm here) of r*.
        for (i, r) in region.radii().iter().enumerate() {
            assert!(
                *r <= r_star && r_star - r < 1e-9,
                "ray {i}: {r} vs {r_star}"
            );
            assert!(region.folds_on_ray(i));
        }
        assert!(!region.whole_active_area());
        assert!((region.nearest_fold_mm().unwrap() - r_star).abs() < 1e-9);
        // The inside rule: below r* (1 − margin) inside, beyond outside.
        for deg in [0.0, 17.3, 90.0, 200.5, 359.9f64] {
            let u = Vector2::new(deg.to_radians().cos(), deg.to_radians().sin());
            let c = region.centre();
            assert!(region.contains(&(c + u * r_star * (1.0 - 1.01 * REGION_MARGIN))));
            let outside = region.check(&(c + u * r_star)).unwrap_err();
            assert!(outside.fold());
            assert!((outside.limit_mm - r_star * (1.0 - REGION_MARGIN)).abs() < 1e-9);
        }
    }
}

#[test]
fn the_reproducers_corner_is_past_the_fold_although_det_is_positive_there() {
    // k1 = −0.02 mm⁻² about (0.5, −0.7): the corner (−4.5, 4.5) is r =
    // √52.04 mm from the centre, past both zeros of (1 + 3k1r²)(1 + k1r²),
    // so the determinant is positive again (+0.085) and the ideal point is
    // mirrored through the centre (1 + k1 r² = −0.04).
    let model = radial(-0.02, 0.0);
    let corner = Vector2::new(-4.5, 4.5);
    let chain = psdcal_model::Model::standard(&model);
    assert!(chain.ideal_point_jacobian(&corner).determinant() > 0.08);
    let ideal = chain.ideal(&corner);
    assert!((ideal - Vector2::new(0.5, -0.7)).dot(&(corner - Vector2::new(0.5, -0.7))) < 0.0);
    let region = ValidRegion::of_sensor_model(&model, &PsdGeometry::default());
    let e = region.check(&corner).unwrap_err();
    assert!(e.fold() && e.distance_mm > e.limit_mm);
}

#[test]
fn non_folding_models_cover_the_whole_active_area() {
    let geometry = PsdGeometry::default();
    // The paper's lenses with its PSD distortion (l1 = −1.3058e-3 folds only
    // at 1/√(3 |l1|) = 16 mm from the electrical centre, beyond the zone),
    // and a distortion-free pinhole.
    let mut lens1 = SensorModel::paper_lens1();
    lens1.distortion.l1 = -1.3058e-3;
    for model in [
        lens1,
        SensorModel::paper_lens2(),
        SensorModel::pinhole(8.0, 0.3, 0.2),
    ] {
        let region = ValidRegion::of_sensor_model(&model, &geometry);
        assert!(region.whole_active_area());
        assert_eq!(region.nearest_fold_mm(), None);
        // Every ray reaches the zone's edge: at θ = 0 from cx, 6.75 − cx.
        let c = region.centre();
        assert!((region.radii()[0] - (0.5 * ZONE_SCALE * 9.0 - c.x)).abs() < 1e-12);
        for corner in [(4.5, 4.5), (-4.5, 4.5), (-4.5, -4.5), (4.5, -4.5)] {
            assert!(region.contains(&Vector2::new(corner.0, corner.1)));
        }
        // Off the active area but in the zone: inside; beyond it: outside.
        assert!(region.contains(&Vector2::new(4.8, 0.0)));
        let far = region.check(&Vector2::new(1e300, 0.0)).unwrap_err();
        assert!(!far.fold());
    }
}

#[test]
fn whole_active_area_is_exact_for_a_fold_just_beyond_a_corner() {
    // Centred lens (cx = cy = 0): the fold circle r* = 1/√(3|k1|). With r*
    // 1 % beyond the corner distance 4.5√2 the whole area is inside; 1 %
    // short of it, the corners are not.
    let corner = 4.5 * 2f64.sqrt();
    for (scale, whole) in [(1.01, true), (0.99, false)] {
        let r_star: f64 = corner * scale;
        let mut m = SensorModel::pinhole(8.0, 0.0, 0.0);
        m.distortion.k1 = -1.0 / (3.0 * r_star * r_star);
        let region = ValidRegion::of_sensor_model(&m, &PsdGeometry::default());
        assert_eq!(region.whole_active_area(), whole, "r* = {r_star}");
        assert_eq!(region.contains(&Vector2::new(4.5, 4.5)), whole);
        assert!(region.contains(&Vector2::new(4.5, 0.0)));
    }
}

/// Brute force: for an asymmetric folding chain (PSD radial about (0, 0),
/// lens radial and tangential about (0.5, −0.7)), every grid point inside
/// has a positive determinant along its whole segment from the centre, and
/// every grid point refused at a fold has a non-positive one on its segment.
#[test]
fn inside_points_have_positive_determinants_all_the_way_from_the_centre() {
    let mut sensor = SensorModel::pinhole(8.0, 0.5, -0.7);
    sensor.distortion.k1 = -0.012;
    sensor.distortion.p1 = 0.01;
    sensor.distortion.l1 = -0.004;
    let model = Model::standard(&sensor);
    let geometry = PsdGeometry::default();
    let region = ValidRegion::of_model(&model, &geometry);
    assert!(!region.whole_active_area());
    let det = |p: &Vector2<f64>| model.ideal_point_jacobian(p).determinant();
    let c = region.centre();
    let (mut inside, mut folded) = (0, 0);
    for iy in 0..=60 {
        for ix in 0..=60 {
            let p = Vector2::new(-4.5 + 0.15 * ix as f64, -4.5 + 0.15 * iy as f64);
            let min_det = (0..=400)
                .map(|k| det(&(c + (p - c) * (k as f64 / 400.0))))
                .fold(f64::INFINITY, f64::min);
            match region.check(&p) {
                Ok(()) => {
                    inside += 1;
                    assert!(min_det > 0.0, "{p:?} inside with det {min_det}");
                }
                Err(e) if e.fold() => {
                    folded += 1;
                    // Refused: the fold lies within the margin (and the
                    // neighbouring ray's spacing) of the point's segment.
                    let beyond = c
                        + (p - c)
                            * ((e.distance_mm.max(e.limit_mm) / e.distance_mm)
                                / (1.0 - REGION_MARGIN)
                                * 1.02);
                    let min_det_beyond = (0..=400)
                        .map(|k| det(&(c + (beyond - c) * (k as f64 / 400.0))))
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        min_det_beyond <= 1e-12,
                        "{p:?} refused, det {min_det_beyond}"
                    );
                }
                Err(e) => panic!("{p:?} beyond the zone: {e:?}"),
            }
        }
    }
    assert!(
        inside > 1000 && folded > 100,
        "{inside} inside, {folded} folded"
    );
}

#[test]
fn regions_from_radii_round_trip_and_refuse_bad_values() {
    let geometry = PsdGeometry::default();
    let region = ValidRegion::of_sensor_model(&radial(-0.02, 0.0), &geometry);
    let back =
        ValidRegion::from_radii(region.centre(), region.radii().to_vec(), &geometry).unwrap();
    assert_eq!(back, region);
    let c = region.centre();
    assert!(ValidRegion::from_radii(c, vec![1.0; 4], &geometry).is_err());
    assert!(ValidRegion::from_radii(c, vec![-1.0; 360], &geometry).is_err());
    assert!(ValidRegion::from_radii(c, vec![f64::NAN; 360], &geometry).is_err());
    assert!(ValidRegion::from_radii(c, vec![20.0; 360], &geometry).is_err());
    assert!(
        ValidRegion::from_radii(Vector2::new(f64::NAN, 0.0), vec![1.0; 360], &geometry).is_err()
    );
    // A model folded at its centre has an empty region.
    let mut m = SensorModel::pinhole(8.0, 0.0, 0.0);
    m.distortion.k1 = f64::NAN;
    let empty = ValidRegion::of_sensor_model(&m, &geometry);
    assert!(!empty.contains(&Vector2::zeros()));
}

/// A PSD map known on a scan's hull (a 6 mm × 5 mm box about (0.3, −0.2),
/// docs/model.md §8.3) ends the region at the hull: each ray's radius is the
/// distance from the optical centre to the box's edge, computed here by
/// hand, and points just inside and just outside the box are answered
/// accordingly.
#[test]
fn a_psd_map_hull_bounds_the_region() {
    use psdcal_model::stages::{MapBasis, MapFrame, PsdMap};
    use psdcal_model::ConvexHull;
    let (x0, x1, y0, y1) = (-2.7, 3.3, -2.7, 2.3);
    let corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)].map(|(x, y)| Vector2::new(x, y));
    let hull = ConvexHull::of_points(&corners).unwrap();
    let map = PsdMap::new(
        MapBasis::Polynomial { order: 2 },
        MapFrame::centred(9.0, 9.0),
        Some(hull),
    )
    .unwrap();
    let model = Model::standard(&radial(1e-3, 0.0))
        .with_stage(0, Box::new(map))
        .unwrap();
    let region = ValidRegion::of_model(&model, &PsdGeometry::default());
    let c = Vector2::new(0.5, -0.7);
    assert!(!region.whole_active_area());
    for (i, r) in region.radii().iter().enumerate() {
        let theta = std::f64::consts::TAU * i as f64 / region.rays() as f64;
        let u = Vector2::new(theta.cos(), theta.sin());
        let tx = if u.x > 0.0 {
            (x1 - c.x) / u.x
        } else if u.x < 0.0 {
            (x0 - c.x) / u.x
        } else {
            f64::INFINITY
        };
        let ty = if u.y > 0.0 {
            (y1 - c.y) / u.y
        } else if u.y < 0.0 {
            (y0 - c.y) / u.y
        } else {
            f64::INFINITY
        };
        let expected = tx.min(ty);
        // The hull admits points 1e-9 mm outside an edge (HULL_TOLERANCE_MM),
        // 1e-9 / cos(angle to the edge normal) mm along the ray.
        assert!((r - expected).abs() < 1e-8, "ray {i}: {r} vs {expected}");
    }
    assert!(region.contains(&Vector2::new(3.2, 0.0)));
    assert!(!region.contains(&Vector2::new(3.35, 0.0)));
    assert!(region.check(&Vector2::new(0.0, 2.4)).is_err());
    assert!(model.in_domain(&Vector2::new(0.0, 2.2)));
    assert!(!model.in_domain(&Vector2::new(0.0, 2.4)));
}

/// Inside a PSD map's hull and before any fold, every point is inside the
/// region: the hull's edge is checked exactly (not by the chord between two
/// rays 4° apart, which cut up to 0.3 mm off a polygon's corners), the rays
/// that end on it end at the domain's edge (not a fold), and a point outside
/// the hull is outside because of the domain. The hull here is an irregular
/// heptagon whose corners lie between rays; "inside" is decided by the
/// half-plane test written out below, not by the hull's own code.
#[test]
fn points_inside_a_psd_maps_hull_are_never_refused_and_its_edge_is_no_fold() {
    use psdcal_model::stages::{MapBasis, MapFrame, PsdMap};
    use psdcal_model::{ConvexHull, RegionEnd};
    let vertices: Vec<Vector2<f64>> = (0..7)
        .map(|k| {
            let t = std::f64::consts::TAU * (k as f64 + 0.37) / 7.0;
            let r = 4.2 + 0.25 * (3.0 * k as f64).sin();
            Vector2::new(0.2 + r * t.cos(), -0.1 + r * t.sin())
        })
        .collect();
    let hull = ConvexHull::from_vertices(vertices.clone()).unwrap();
    let map = PsdMap::new(
        MapBasis::Polynomial { order: 2 },
        MapFrame::centred(9.0, 9.0),
        Some(hull),
    )
    .unwrap();
    let model = Model::standard(&radial(1e-4, 0.0))
        .with_stage(0, Box::new(map))
        .unwrap();
    let region = ValidRegion::of_model(&model, &PsdGeometry::default());
    assert!(region.ends().iter().all(|e| *e == RegionEnd::DomainEdge));
    assert_eq!(region.nearest_fold_mm(), None);
    let inside_by_hand = |p: &Vector2<f64>, margin: f64| {
        (0..7).all(|i| {
            let (a, b) = (vertices[i], vertices[(i + 1) % 7]);
            let e = b - a;
            (e.x * (p.y - a.y) - e.y * (p.x - a.x)) / e.norm() > margin
        })
    };
    let (mut inside, mut outside) = (0, 0);
    for i in 0..=180 {
        for j in 0..=180 {
            let p = Vector2::new(-4.5 + 0.05 * i as f64, -4.5 + 0.05 * j as f64);
            if inside_by_hand(&p, 1e-6) {
                inside += 1;
                assert!(region.contains(&p), "{p:?} is inside the hull");
            } else if !inside_by_hand(&p, -1e-6) {
                outside += 1;
                let o = region.check(&p).unwrap_err();
                assert_eq!(o.end, RegionEnd::DomainEdge, "{p:?}");
                assert!(o.limit_mm < o.distance_mm);
            }
        }
    }
    assert!(inside > 10_000 && outside > 1_000, "{inside} {outside}");
    // A region read back from its radii learns how its rays end from the
    // model's domain.
    let stored = ValidRegion::from_radii(
        region.centre(),
        region.radii().to_vec(),
        &PsdGeometry::default(),
    )
    .unwrap()
    .with_domain(model.measured_domain().cloned());
    assert_eq!(stored, region);
}

/// The exit distance of a ray from a hull against a bisection of its inside
/// test.
#[test]
fn hull_exit_distance_matches_a_bisection_of_the_inside_test() {
    use psdcal_model::ConvexHull;
    let pts: Vec<Vector2<f64>> = (0..40)
        .map(|k| {
            let t = 2.399963 * k as f64;
            let r = 3.0 + (k % 5) as f64 * 0.3;
            Vector2::new(r * t.cos(), 0.8 * r * t.sin())
        })
        .collect();
    let hull = ConvexHull::of_points(&pts).unwrap();
    let c = Vector2::new(0.3, -0.2);
    for i in 0..37 {
        let t = std::f64::consts::TAU * (i as f64 + 0.1) / 37.0;
        let u = Vector2::new(t.cos(), t.sin());
        let (mut lo, mut hi) = (0.0, 20.0);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if hull.contains(&(c + u * mid)) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let exit = hull.exit_distance(&c, &u);
        assert!((exit - lo).abs() < 1e-8, "ray {i}: {exit} vs {lo}");
    }
    assert_eq!(
        hull.exit_distance(&Vector2::new(50.0, 0.0), &Vector2::x()),
        0.0
    );
}
