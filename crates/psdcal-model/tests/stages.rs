//! The shared stage suite (docs/model.md §8): every stage in [`all_stages`] is
//! checked, over each of its example parameter blocks and points across the
//! active area, for its Jacobians with respect to the input point and to its
//! parameters against central finite differences; every chain built from
//! the examples for its round trip (measured → ideal → measured) and for
//! the Jacobians of the ray, the back-projection and the projection. Adding
//! a stage to [`all_stages`] puts it under all of these tests.

mod common;

use common::{
    check_jacobian, check_jacobian_with_floor, example_poses, example_template_points, POSE_SCALES,
};
use nalgebra::{DMatrix, DVector, Matrix2, Vector2};
use psdcal_model::stages::lens::LensCoefficients;
use psdcal_model::stages::pinhole::PinholeIntrinsics;
use psdcal_model::stages::{Aspect, Gains, Lens, MapBasis, MapFrame, Pinhole, PsdMap, PsdRadial};
use psdcal_model::{
    Amplitudes, ChannelGains, Model, Pose, PsdGeometry, SensorModel, Stage, StageJacobian,
};
use psdcal_testkit::PolyField;

const REL: f64 = 1e-6;

/// Every stage under test: the standard ones and the test-only stage with a
/// 200-coefficient block.
fn all_stages() -> Vec<Box<dyn Stage>> {
    vec![
        Box::new(PsdRadial::new()),
        Box::new(Lens::new()),
        Box::new(Pinhole::new()),
        Box::new(Aspect::new()),
        Box::new(PolyField::new(10, 4.5)),
        Box::new(psd_map(MapBasis::Polynomial { order: 5 })),
        Box::new(psd_map(MapBasis::Spline {
            cells_x: 5,
            cells_y: 4,
        })),
    ]
}

/// A PSD map over the 9 mm active area, defined everywhere (the suite's
/// points reach the corners; its hull is tested in tests/valid_region.rs).
fn psd_map(basis: MapBasis) -> PsdMap {
    PsdMap::new(basis, MapFrame::centred(9.0, 9.0), None).unwrap()
}

fn points() -> Vec<Vector2<f64>> {
    let mut p = vec![Vector2::new(0.0, 0.0), Vector2::new(1e-7, -2e-7)];
    for i in -2..=2 {
        for j in -2..=2 {
            p.push(Vector2::new(2.1 * i as f64 + 0.13, 2.05 * j as f64 - 0.07));
        }
    }
    p
}

fn dv(v: Vector2<f64>) -> DVector<f64> {
    DVector::from_row_slice(v.as_slice())
}

#[test]
fn every_stage_has_a_consistent_block_and_examples() {
    for stage in all_stages() {
        let n = stage.parameters().len();
        assert!(n > 0, "{}", stage.kind());
        let examples = stage.example_parameters();
        assert!(
            examples.len() >= 2,
            "{}: at least two examples",
            stage.kind()
        );
        for block in &examples {
            assert_eq!(block.len(), n, "{}: example length", stage.kind());
            stage.validate(block).unwrap();
        }
        let mut bad = examples[0].clone();
        bad[n - 1] = f64::NAN;
        assert!(
            stage.validate(&bad).is_err(),
            "{}: NaN refused",
            stage.kind()
        );
    }
}

#[test]
fn stage_jacobians_match_finite_differences() {
    for stage in all_stages() {
        let n = stage.parameters().len();
        let scales: Vec<f64> = stage.parameters().iter().map(|p| p.scale).collect();
        for (e, block) in stage.example_parameters().iter().enumerate() {
            for p in points() {
                let name = format!("{} example {e} at {p:?}", stage.kind());
                let mut d_in = Matrix2::zeros();
                let mut d_par = vec![0.0; 2 * n];
                let out = stage.apply(
                    block,
                    &p,
                    Some(StageJacobian {
                        wrt_input: &mut d_in,
                        wrt_params: &mut d_par,
                    }),
                );
                assert_eq!(
                    out,
                    stage.apply(block, &p, None),
                    "{name}: same value with Jacobians"
                );
                check_jacobian(
                    &format!("{name} wrt input"),
                    &dv(p),
                    &[1.0, 1.0],
                    &|x| dv(stage.apply(block, &Vector2::new(x[0], x[1]), None)),
                    &DMatrix::from_column_slice(2, 2, d_in.as_slice()),
                    REL,
                );
                // Floor: the rounding of a central difference with a scaled
                // step of 1e-5 on an output of size |out| (≈ 2ε|out|/1e-5),
                // for columns that vanish at the point.
                check_jacobian_with_floor(
                    &format!("{name} wrt parameters"),
                    &DVector::from_row_slice(block),
                    &scales,
                    &|x| dv(stage.apply(x.as_slice(), &p, None)),
                    &DMatrix::from_column_slice(2, n, &d_par),
                    REL,
                    1e-10 * out.norm().max(1.0),
                );
            }
        }
    }
}

/// Chains built from the distortion stages' examples (the pinhole's first
/// example block: f = 8 mm, centre from the lens).
fn example_chains() -> Vec<(String, Model)> {
    let mut chains = Vec::new();
    for stage in all_stages().into_iter().filter(|s| s.kind() != "pinhole") {
        for (e, block) in stage.example_parameters().into_iter().enumerate() {
            for extra in [false, true] {
                // Alone, or after the paper's PSD and lens-2 distortion.
                let mut stages: Vec<Box<dyn Stage>> = vec![stage.clone_box()];
                let mut values: Vec<(String, f64)> = stage
                    .parameters()
                    .iter()
                    .zip(&block)
                    .map(|(p, v)| (p.name.clone(), *v))
                    .collect();
                if extra && stage.kind() != "lens" {
                    stages.push(Box::new(Lens::new()));
                    for (name, v) in [("cx", 0.5), ("cy", -0.7), ("k1", 1e-2), ("k2", 3e-5)] {
                        if !values.iter().any(|(n, _)| n == name) {
                            values.push((name.into(), v));
                        }
                    }
                } else if extra {
                    stages.insert(0, Box::new(PsdRadial::new()));
                    values.push(("l1".into(), SensorModel::PAPER_L1));
                }
                values.push(("f".into(), 8.0));
                let named: Vec<(&str, f64)> =
                    values.iter().map(|(n, v)| (n.as_str(), *v)).collect();
                let model = Model::new(stages, None, &named).unwrap();
                chains.push((format!("{} example {e} extra {extra}", stage.kind()), model));
            }
        }
    }
    chains
}

fn model_vector(model: &Model) -> DVector<f64> {
    DVector::from_row_slice(model.values())
}

fn with_values(model: &Model, x: &DVector<f64>) -> Model {
    let mut m = model.clone();
    m.set_values(x.as_slice());
    m
}

fn scales(model: &Model) -> Vec<f64> {
    model.parameters().iter().map(|p| p.scale).collect()
}

#[test]
fn chains_round_trip_measured_ideal_measured() {
    for (name, model) in example_chains() {
        for m in points() {
            let ideal = model.ideal(&m);
            let back = model.measured_from_ideal(&ideal).unwrap();
            assert!((back - m).norm() < 1e-10, "{name} at {m:?}: {back:?}");
            let ab = model.ray(&m);
            assert!((model.ideal_of_ray(&ab) - ideal).norm() < 1e-12, "{name}");
        }
    }
}

#[test]
fn chain_ray_jacobians_match_finite_differences() {
    for (name, model) in example_chains() {
        let mut jac = model.jacobian_buffer();
        for m in points() {
            let ab = model.ray_with_jacobians(&m, &mut jac);
            assert_eq!(ab, model.ray(&m), "{name}");
            check_jacobian(
                &format!("ray wrt point [{name} {m:?}]"),
                &dv(m),
                &[1.0, 1.0],
                &|x| dv(model.ray(&Vector2::new(x[0], x[1]))),
                &DMatrix::from_column_slice(2, 2, jac.wrt_point.as_slice()),
                REL,
            );
            check_jacobian(
                &format!("ray wrt parameters [{name} {m:?}]"),
                &model_vector(&model),
                &scales(&model),
                &|x| dv(with_values(&model, x).ray(&m)),
                &DMatrix::from_column_slice(2, model.len(), &jac.wrt_params),
                REL,
            );
        }
    }
}

fn pose_vector(p: &Pose) -> DVector<f64> {
    DVector::from_row_slice(&p.to_array())
}

fn pose_of(x: &DVector<f64>) -> Pose {
    let mut a = [0.0; 6];
    a.copy_from_slice(x.as_slice());
    Pose::from_array(&a)
}

#[test]
fn chain_projection_jacobians_match_finite_differences() {
    for (name, model) in example_chains() {
        let mut jac = model.jacobian_buffer();
        for pose in example_poses() {
            let rotation = pose.rotation_jacobian();
            for xy in example_template_points() {
                let Ok(m) = model.project(&pose, &xy) else {
                    continue;
                };
                let (m2, j) = model
                    .project_with_jacobians(&pose, &rotation, &xy, &mut jac)
                    .unwrap();
                assert!((m2 - m).norm() == 0.0);
                let back = model.back_project(&pose, &m).unwrap();
                assert!(
                    (back - xy).norm() < 1e-8,
                    "{name}: round trip {back:?} vs {xy:?}"
                );
                let label = format!("[{name} {xy:?} {:?}]", pose.t);
                check_jacobian(
                    &format!("project wrt parameters {label}"),
                    &model_vector(&model),
                    &scales(&model),
                    &|x| dv(with_values(&model, x).project(&pose, &xy).unwrap()),
                    &DMatrix::from_column_slice(2, model.len(), &jac.wrt_params),
                    REL,
                );
                check_jacobian(
                    &format!("project wrt pose {label}"),
                    &pose_vector(&pose),
                    &POSE_SCALES,
                    &|x| dv(model.project(&pose_of(x), &xy).unwrap()),
                    &DMatrix::from_column_slice(2, 6, j.wrt_pose.as_slice()),
                    REL,
                );
                check_jacobian(
                    &format!("project wrt template {label}"),
                    &dv(xy),
                    &[100.0, 100.0],
                    &|x| dv(model.project(&pose, &Vector2::new(x[0], x[1])).unwrap()),
                    &DMatrix::from_column_slice(2, 2, j.wrt_point.as_slice()),
                    REL,
                );
                let (_, jb) = model
                    .back_project_with_jacobians(&pose, &rotation, &m, &mut jac)
                    .unwrap();
                check_jacobian(
                    &format!("back-project wrt parameters {label}"),
                    &model_vector(&model),
                    &scales(&model),
                    &|x| dv(with_values(&model, x).back_project(&pose, &m).unwrap()),
                    &DMatrix::from_column_slice(2, model.len(), &jac.wrt_params),
                    REL,
                );
                check_jacobian(
                    &format!("back-project wrt pose {label}"),
                    &pose_vector(&pose),
                    &POSE_SCALES,
                    &|x| dv(model.back_project(&pose_of(x), &m).unwrap()),
                    &DMatrix::from_column_slice(2, 6, jb.wrt_pose.as_slice()),
                    REL,
                );
                check_jacobian(
                    &format!("back-project wrt point {label}"),
                    &dv(m),
                    &[1.0, 1.0],
                    &|x| {
                        dv(model
                            .back_project(&pose, &Vector2::new(x[0], x[1]))
                            .unwrap())
                    },
                    &DMatrix::from_column_slice(2, 2, jb.wrt_point.as_slice()),
                    REL,
                );
            }
        }
    }
}

#[test]
fn the_standard_chain_is_the_sensor_models_stages() {
    for (name, sensor) in common::example_models() {
        let model = Model::standard(&sensor);
        assert_eq!(model.sensor_model(), sensor, "{name}");
        let (i, d) = (&sensor.intrinsics, &sensor.distortion);
        let lens = LensCoefficients {
            c: Vector2::new(i.cx, i.cy),
            k: [d.k1, d.k2, d.k3],
            p: [d.p1, d.p2],
        };
        let pinhole = PinholeIntrinsics {
            f: i.f,
            c: Vector2::new(i.cx, i.cy),
            skew: i.skew,
        };
        for m in points() {
            // PSD radial, then lens, then pinhole: the same arithmetic.
            let ideal = Lens::eval(&lens, &PsdRadial::eval(d.l1, d.l2, &m, None), None);
            assert_eq!(model.ideal(&m), ideal, "{name}");
            assert_eq!(
                model.ray(&m),
                Pinhole::eval(&pinhole, &ideal, None),
                "{name}"
            );
        }
        for pose in example_poses() {
            for xy in example_template_points() {
                if let (Ok(a), Ok(b)) = (
                    model.project(&pose, &xy),
                    model.project_to_tolerance(&pose, &xy),
                ) {
                    assert!((a - b).norm() < 1e-12, "{name}: {a:?} vs {b:?}");
                    let ba = model.back_project(&pose, &a).unwrap();
                    let bb = model.back_project(&pose, &b).unwrap();
                    assert!((ba - bb).norm() < 1e-9, "{name}");
                }
            }
        }
    }
}

#[test]
fn gains_stage_jacobian_matches_finite_differences() {
    let geometry = PsdGeometry::default();
    let stage = Gains::new(geometry);
    let amps = [
        Amplitudes {
            vx1: 1.0,
            vx2: 1.2,
            vy1: 0.9,
            vy2: 1.1,
        },
        Amplitudes {
            vx1: 0.2,
            vx2: 2.0,
            vy1: 0.7,
            vy2: 0.4,
        },
    ];
    for block in Gains::example_parameters() {
        for a in &amps {
            let (p, j) = stage.apply_with_jacobian(&block, a).unwrap();
            assert_eq!(p, stage.apply(&block, a).unwrap());
            check_jacobian(
                "gains wrt parameters",
                &DVector::from_row_slice(&block),
                &[1e-2; 3],
                &|x| dv(stage.apply(x.as_slice(), a).unwrap()),
                &DMatrix::from_column_slice(2, 3, j.as_slice()),
                REL,
            );
        }
    }
    let model = Model::standard_with_gains(
        &SensorModel::paper_lens2(),
        geometry,
        &ChannelGains {
            x2: 1.01,
            y1: 0.99,
            y2: 1.02,
        },
    );
    assert_eq!(model.names()[11..], ["g_x2", "g_y1", "g_y2"]);
    assert_eq!(model.gains().unwrap().y2, 1.02);
}

#[test]
fn a_parameter_shared_by_two_stages_is_one_column() {
    let model = Model::standard(&SensorModel::paper_lens2());
    assert_eq!(
        model.names(),
        ["f", "cx", "cy", "skew", "k1", "k2", "k3", "p1", "p2", "l1", "l2"]
    );
    let big = model
        .with_stage(0, Box::new(PolyField::new(10, 4.5)))
        .unwrap();
    assert_eq!(big.len(), 211);
    assert_eq!(big.stage_kinds(), ["test_poly_field", "psd_radial", "lens"]);
    assert!(Model::new(vec![Box::new(Pinhole::new())], None, &[]).is_err());
}

#[test]
fn restricted_jacobians_are_the_full_ones_column_for_column() {
    // A fit's buffer computes its freed columns only: those are the full
    // computation's to the bit (each column is its own chain of products),
    // the others stay zero; ray, projection and back-projection alike.
    for (name, model) in example_chains() {
        let every: Vec<usize> = (0..model.len()).collect();
        for chosen in [
            every.clone(),
            every.iter().copied().step_by(2).collect(),
            vec![],
        ] {
            let mut full = model.jacobian_buffer();
            let mut part = model.jacobian_buffer();
            part.restrict_to(&chosen);
            let same = |full: &psdcal_model::ChainJacobian,
                        part: &psdcal_model::ChainJacobian,
                        what: &str| {
                for k in 0..model.len() {
                    let expected = if chosen.contains(&k) {
                        full.column(k)
                    } else {
                        Vector2::zeros()
                    };
                    assert_eq!(part.column(k), expected, "{name} {what} column {k}");
                }
                assert_eq!(part.wrt_point, full.wrt_point, "{name} {what}");
            };
            for m in points() {
                for jac in [&mut full, &mut part] {
                    model.ray_with_jacobians(&m, jac);
                }
                same(&full, &part, "ray");
            }
            for pose in example_poses() {
                let rotation = pose.rotation_jacobian();
                for xy in example_template_points() {
                    let Ok(m) = model.project(&pose, &xy) else {
                        continue;
                    };
                    for jac in [&mut full, &mut part] {
                        model
                            .project_with_jacobians(&pose, &rotation, &xy, jac)
                            .unwrap();
                    }
                    same(&full, &part, "projection");
                    for jac in [&mut full, &mut part] {
                        model
                            .back_project_with_jacobians(&pose, &rotation, &m, jac)
                            .unwrap();
                    }
                    same(&full, &part, "back-projection");
                }
            }
        }
    }
}

/// The aspect stage before the pinhole is the pinhole with a y focal length
/// of its own, written out independently: `x = f X/Z + γ Y/Z + cx`,
/// `y = f (1 + a) Y/Z + cy` (docs/model.md §3.3).
#[test]
fn aspect_is_the_pinhole_with_its_own_y_focal_length() {
    let (f, a, cx, cy, skew) = (8.0, -0.5, 0.3, -0.4, 0.02);
    let model = Model::new(
        vec![Box::new(Aspect::new())],
        None,
        &[("f", f), ("a", a), ("cx", cx), ("cy", cy), ("skew", skew)],
    )
    .unwrap();
    for (xz, yz) in [(0.0, 0.0), (0.2, -0.1), (-0.35, 0.27), (0.05, 0.4)] {
        let measured = Vector2::new(f * xz + skew * yz + cx, f * (1.0 + a) * yz + cy);
        let ray = model.ray(&measured);
        assert!((ray - Vector2::new(xz, yz)).norm() < 1e-14, "{ray:?}");
    }
}
