//! Round trips and closed-form cases of every model map, and the typed errors
//! outside the model's valid region.

mod common;

use common::{example_models, example_poses, example_template_points};
use nalgebra::{Vector2, Vector3};
use proptest::prelude::*;
use psdcal_model::psd::{electrode_currents, impact_point, impact_point_with_gains};
use psdcal_model::{ChannelGains, Model, ModelError, Pose, PsdGeometry, SensorModel};

/// 41 × 41 points over the 9 × 9 mm active area, edges included.
fn sensor_grid() -> impl Iterator<Item = Vector2<f64>> {
    (0..41).flat_map(|i| {
        (0..41).map(move |j| Vector2::new(-4.5 + 0.225 * i as f64, -4.5 + 0.225 * j as f64))
    })
}

/// The round-trip cases: both lenses, with and without the paper's
/// PSD distortion, and with tangential terms.
fn round_trip_models() -> Vec<(String, SensorModel)> {
    let mut out = Vec::new();
    for (lens, base) in [
        ("lens1", SensorModel::paper_lens1()),
        ("lens2", SensorModel::paper_lens2()),
    ] {
        for l1 in [0.0, SensorModel::PAPER_L1] {
            for tangential in [false, true] {
                let mut m = base;
                m.distortion.l1 = l1;
                if tangential {
                    m.distortion.p1 = 4e-4;
                    m.distortion.p2 = -3e-4;
                }
                out.push((format!("{lens} l1={l1} tangential={tangential}"), m));
            }
        }
    }
    out
}

#[test]
fn distortion_round_trip_on_the_sensor_grid() {
    for (name, model) in round_trip_models() {
        let model = Model::standard(&model);
        for polished in [true, false] {
            let inverse = |ideal: &Vector2<f64>| {
                if polished {
                    model.measured_from_ideal(ideal)
                } else {
                    model.measured_from_ideal_to_tolerance(ideal)
                }
            };
            let mut worst: f64 = 0.0;
            for ideal in sensor_grid() {
                let measured = inverse(&ideal).unwrap_or_else(|e| panic!("{name}: {ideal:?}: {e}"));
                worst = worst.max((model.ideal(&measured) - ideal).norm());
            }
            assert!(
                worst <= 1e-10,
                "{name}: ideal → measured → ideal error {worst:.3e} mm"
            );
            let mut worst: f64 = 0.0;
            for measured in sensor_grid() {
                let back = inverse(&model.ideal(&measured)).unwrap();
                worst = worst.max((back - measured).norm());
            }
            assert!(
                worst <= 1e-10,
                "{name}: measured → ideal → measured error {worst:.3e} mm"
            );
        }
    }
}

/// The inverse started near the answer (`measured_from_ideal_near`, as
/// the image-plane residuals start it at the measured point) lands on the
/// same point as the inverse started at the ideal point: within the
/// inverse's 1e-12 mm tolerance, from starts 0.05 mm off (noise far above
/// any real point's) over the whole sensor; and it is the exact preimage
/// (ideal → measured → ideal to 1e-10 mm, as the plain round trip).
#[test]
fn inverse_started_near_the_answer_is_the_same_point() {
    for (name, model) in round_trip_models() {
        let chain = Model::standard(&model);
        let mut worst: f64 = 0.0;
        for (k, measured) in sensor_grid().enumerate() {
            let ideal = chain.ideal(&measured);
            let off = 0.05 * Vector2::new((1.7 * k as f64).sin(), (2.3 * k as f64).cos());
            let plain = chain.measured_from_ideal(&ideal);
            let near = chain.measured_from_ideal_near(&ideal, &(measured + off));
            match (plain, near) {
                (Ok(a), Ok(b)) => {
                    worst = worst.max((a - b).norm());
                    assert!(
                        (chain.ideal(&b) - ideal).norm() <= 1e-10,
                        "{name}: {measured:?}"
                    );
                }
                (a, b) => panic!("{name}: {measured:?}: {a:?} against {b:?}"),
            }
        }
        assert!(
            worst <= 2e-12,
            "{name}: the two inverses differ by {worst:.3e} mm"
        );
    }
}

#[test]
fn ideal_closed_form_cases() {
    // Lens radial only: a point 3 mm right of the optical centre moves out by k1 r³.
    let lens1 = Model::standard(&SensorModel::paper_lens1());
    let m = Vector2::new(0.5 + 3.0, -0.7);
    let ideal = lens1.ideal(&m);
    assert!((ideal - Vector2::new(0.5 + 3.0 * (1.0 + 2e-3 * 9.0), -0.7)).norm() < 1e-15);
    // The optical centre itself is a fixed point of the lens terms.
    let lens2 = Model::standard(&SensorModel::paper_lens2());
    assert!((lens2.ideal(&Vector2::new(0.5, -0.7)) - Vector2::new(0.5, -0.7)).norm() < 1e-15);
    // PSD radial only: scales by (1 + l1 h²) about the electrical centre.
    let mut psd = SensorModel::pinhole(8.0, 0.0, 0.0);
    psd.distortion.l1 = SensorModel::PAPER_L1;
    let p = Model::standard(&psd).ideal(&Vector2::new(3.0, 4.0));
    assert!((p - Vector2::new(3.0, 4.0) * (1.0 + SensorModel::PAPER_L1 * 25.0)).norm() < 1e-15);
    // Tangential only, at (dx, dy) = (1, 2): tx = p1 (5 + 2) + 2 p2·2, ty = p2 (5 + 8) + 2 p1·2.
    let mut tan = SensorModel::pinhole(8.0, 0.0, 0.0);
    tan.distortion.p1 = 1e-3;
    tan.distortion.p2 = 2e-3;
    let t = Model::standard(&tan).ideal(&Vector2::new(1.0, 2.0)) - Vector2::new(1.0, 2.0);
    assert!((t - Vector2::new(1e-3 * 7.0 + 4.0 * 2e-3, 2e-3 * 13.0 + 4.0 * 1e-3)).norm() < 1e-15);
}

#[test]
fn pinhole_closed_form_cases() {
    let sensor = SensorModel::paper_lens2();
    let model = Model::standard(&sensor);
    // On the optical axis: the optical centre.
    let on_axis = model
        .ideal_of_point(&Vector3::new(0.0, 0.0, 1234.0))
        .unwrap();
    assert_eq!(on_axis, Vector2::new(0.5, -0.7));
    // 45° off axis in x: f to the right of the centre.
    let p = model
        .ideal_of_point(&Vector3::new(1000.0, 0.0, 1000.0))
        .unwrap();
    assert!((p - Vector2::new(8.5, -0.7)).norm() < 1e-14);
    // Skew shifts x by γ · Yc/Zc.
    let mut skewed = sensor;
    skewed.intrinsics.skew = 0.25;
    let q = Model::standard(&skewed)
        .ideal_of_point(&Vector3::new(0.0, 500.0, 1000.0))
        .unwrap();
    assert!((q - Vector2::new(0.5 + 0.125, -0.7 + 4.0)).norm() < 1e-14);
}

#[test]
fn projection_back_projection_round_trip() {
    for (name, model) in example_models() {
        let model = Model::standard(&model);
        for pose in example_poses() {
            for xy in example_template_points() {
                let measured = model.project(&pose, &xy).unwrap();
                let back = model.back_project(&pose, &measured).unwrap();
                assert!(
                    (back - xy).norm() < 1e-9,
                    "{name}: {xy:?} → {measured:?} → {back:?}"
                );
            }
        }
    }
}

#[test]
fn outside_the_valid_region_is_a_typed_error() {
    // Strong pin-cushion correction x = xd (1 − 0.01 xd²) peaks at x ≈ 3.85 mm:
    // an ideal point at 10 mm has no measured point.
    let mut folded = SensorModel::pinhole(8.0, 0.0, 0.0);
    folded.distortion.k1 = -0.01;
    let folded = Model::standard(&folded);
    match folded.measured_from_ideal(&Vector2::new(10.0, 0.0)) {
        Err(ModelError::SingularDistortion { .. })
        | Err(ModelError::DistortionNotConverged { .. }) => {}
        other => panic!("expected a distortion error, got {other:?}"),
    }
    assert!(matches!(
        folded.measured_from_ideal(&Vector2::new(f64::NAN, 0.0)),
        Err(ModelError::NonFinite { .. })
    ));
    let model = Model::standard(&SensorModel::paper_lens2());
    let behind = Pose::new(Vector3::zeros(), Vector3::new(0.0, 0.0, -500.0));
    assert!(matches!(
        model.project(&behind, &Vector2::new(0.0, 0.0)),
        Err(ModelError::BehindSensor { .. })
    ));
    // Template plane seen edge-on (rotated 90° about x): rays run parallel to it.
    let edge_on = Pose::new(
        Vector3::new(std::f64::consts::FRAC_PI_2, 0.0, 0.0),
        Vector3::new(0.0, 0.0, 1000.0),
    );
    assert!(matches!(
        model.back_project(&edge_on, &Vector2::new(0.5, -0.7)),
        Err(ModelError::RayMissesPlane { .. })
    ));
}

#[test]
fn unequal_gains_bias_the_centre_and_dividing_them_out_removes_it() {
    let geometry = PsdGeometry::default();
    let gains = ChannelGains {
        x2: 1.05,
        y1: 0.97,
        y2: 1.08,
    };
    let balanced = electrode_currents(&geometry, &Vector2::zeros(), 1.0);
    let measured = balanced.apply_gains(&gains);
    // At the centre every current is I0/4, so S = (1 + g_x2 + g_y1 + g_y2)/4 and
    // x = (Lx/2)(g_x2 + g_y1 − 1 − g_y2)/(1 + g_x2 + g_y1 + g_y2), likewise y.
    let sum = 1.0 + gains.x2 + gains.y1 + gains.y2;
    let expected = Vector2::new(
        4.5 * (gains.x2 + gains.y1 - 1.0 - gains.y2) / sum,
        4.5 * (gains.x2 + gains.y2 - 1.0 - gains.y1) / sum,
    );
    let biased = impact_point(&geometry, &measured).unwrap();
    assert!((biased - expected).norm() < 1e-15);
    assert!(biased.norm() > 0.05, "the bias is real: {biased:?}");
    let corrected = impact_point_with_gains(&geometry, &measured, &gains).unwrap();
    assert!(corrected.norm() < 1e-15);
}

#[test]
fn electrode_corners_map_to_themselves() {
    let geometry = PsdGeometry { lx: 9.0, ly: 6.0 };
    for corner in [
        Vector2::new(4.5, 3.0),
        Vector2::new(4.5, -3.0),
        Vector2::new(-4.5, -3.0),
        Vector2::new(-4.5, 3.0),
    ] {
        let amps = electrode_currents(&geometry, &corner, 1.0);
        // All the current goes to the corner's own electrode.
        let nonzero = [amps.vx1, amps.vx2, amps.vy1, amps.vy2]
            .iter()
            .filter(|v| v.abs() > 0.0)
            .count();
        assert_eq!(nonzero, 1);
        assert!((impact_point(&geometry, &amps).unwrap() - corner).norm() < 1e-15);
    }
}

proptest! {
    #[test]
    fn pin_cushion_forward_inverse_round_trip(
        x in -4.5f64..4.5, y in -3.0f64..3.0, i0 in 1e-9f64..1e3,
        g in (0.8f64..1.2, 0.8f64..1.2, 0.8f64..1.2),
    ) {
        let geometry = PsdGeometry { lx: 9.0, ly: 6.0 };
        let gains = ChannelGains { x2: g.0, y1: g.1, y2: g.2 };
        let point = Vector2::new(x, y);
        let amps = electrode_currents(&geometry, &point, i0);
        prop_assert!((impact_point(&geometry, &amps).unwrap() - point).norm() < 1e-12);
        let through_gains = amps.apply_gains(&gains);
        prop_assert!((impact_point_with_gains(&geometry, &through_gains, &gains).unwrap() - point).norm() < 1e-12);
    }

    #[test]
    fn pose_inverse_round_trip(
        r in (-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0),
        t in (-1e3f64..1e3, -1e3f64..1e3, -1e3f64..1e3),
        p in (-500f64..500.0, -500f64..500.0, -500f64..500.0),
    ) {
        let pose = Pose::new(Vector3::new(r.0, r.1, r.2), Vector3::new(t.0, t.1, t.2));
        let p = Vector3::new(p.0, p.1, p.2);
        prop_assert!((pose.inverse().transform(&pose.transform(&p)) - p).norm() < 1e-9);
        let rot = pose.rotation();
        prop_assert!((rot * rot.transpose() - nalgebra::Matrix3::identity()).norm() < 1e-14);
        let again = Pose::from_rotation(&rot, pose.t);
        prop_assert!((again.rotation() - rot).norm() < 1e-12);
    }
}

/// `joint` is the inverse of `sub` and `cross` on two disjoint name sets,
/// and refuses a cross block of the wrong shape.
#[test]
fn joint_covariance_splits_back_into_its_blocks() {
    use nalgebra::DMatrix;
    use psdcal_model::ParameterCovariance;
    let names = ["f", "cx", "m0", "m1", "m2"];
    // A symmetric positive-definite matrix built as A Aᵀ + I.
    let a = DMatrix::from_fn(5, 5, |i, j| ((i * 7 + j * 3) % 5) as f64 - 2.0);
    let full = ParameterCovariance::new(
        names.iter().map(|n| n.to_string()).collect(),
        &a * a.transpose() + DMatrix::identity(5, 5),
    )
    .unwrap();
    let (first, second) = (["f", "cx"], ["m0", "m1", "m2"]);
    let cross = full.cross(&second, &first).unwrap();
    assert_eq!(cross.shape(), (3, 2));
    let joint = full
        .sub(&first)
        .unwrap()
        .joint(&full.sub(&second).unwrap(), &cross)
        .unwrap();
    assert_eq!(joint, full);
    let bad = full
        .sub(&first)
        .unwrap()
        .joint(&full.sub(&second).unwrap(), &cross.transpose());
    assert!(bad.is_err());
}
