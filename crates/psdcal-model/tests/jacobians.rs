//! The shared Jacobian suite: every analytic Jacobian of the model against
//! central finite differences (relative 1e-6), over every example model,
//! pose and point.

mod common;

use common::{
    check_jacobian, example_models, example_poses, example_template_points, MODEL_SCALES,
    POSE_SCALES,
};
use nalgebra::{DMatrix, DVector, Vector2, Vector3};
use psdcal_model::psd::{
    electrode_currents, impact_point, impact_point_amplitude_jacobian, impact_point_gain_jacobian,
    impact_point_with_gains,
};
use psdcal_model::{Amplitudes, ChannelGains, Model, Pose, PsdGeometry, SensorModel, N_PARAMS};

const REL: f64 = 1e-6;

fn dyn_mat<const R: usize, const C: usize>(m: &nalgebra::SMatrix<f64, R, C>) -> DMatrix<f64> {
    DMatrix::from_column_slice(R, C, m.as_slice())
}

fn model_vec(m: &SensorModel) -> DVector<f64> {
    DVector::from_row_slice(&m.to_array())
}

/// The standard chain of a parameter vector in `Param::ALL` order (the
/// standard chain's flat order).
fn chain_of(v: &DVector<f64>) -> Model {
    let mut a = [0.0; N_PARAMS];
    a.copy_from_slice(v.as_slice());
    Model::standard(&SensorModel::from_array(&a))
}

/// A chain Jacobian's `∂/∂θ` (2×P, column-major) as a matrix.
fn params_mat(wrt_params: &[f64]) -> DMatrix<f64> {
    DMatrix::from_column_slice(2, wrt_params.len() / 2, wrt_params)
}

fn pose_of(v: &DVector<f64>) -> Pose {
    let mut a = [0.0; 6];
    a.copy_from_slice(v.as_slice());
    Pose::from_array(&a)
}

fn v2(v: Vector2<f64>) -> DVector<f64> {
    DVector::from_row_slice(v.as_slice())
}

fn measured_points() -> Vec<Vector2<f64>> {
    vec![
        Vector2::new(0.0, 0.0),
        Vector2::new(0.2, -0.1),
        Vector2::new(-4.0, -3.5),
        Vector2::new(3.9, 4.2),
        Vector2::new(4.4, -4.4),
        Vector2::new(-2.0, 3.0),
    ]
}

#[test]
fn ideal_jacobians() {
    for (name, model) in example_models() {
        let chain = Model::standard(&model);
        let mut jac = chain.jacobian_buffer();
        for m in measured_points() {
            let ideal = chain.ideal_with_jacobians(&m, &mut jac);
            assert!((ideal - chain.ideal(&m)).norm() == 0.0);
            assert_eq!(jac.wrt_point, chain.ideal_point_jacobian(&m));
            check_jacobian(
                &format!("ideal wrt point [{name} {m:?}]"),
                &v2(m),
                &[1.0; 2],
                &|x| v2(chain.ideal(&Vector2::new(x[0], x[1]))),
                &dyn_mat(&jac.wrt_point),
                REL,
            );
            check_jacobian(
                &format!("ideal wrt model [{name} {m:?}]"),
                &model_vec(&model),
                &MODEL_SCALES,
                &|x| v2(chain_of(x).ideal(&m)),
                &params_mat(&jac.wrt_params),
                REL,
            );
        }
    }
}

#[test]
fn inverse_jacobian_is_inverse_of_ideal_jacobian() {
    for (name, model) in example_models() {
        let chain = Model::standard(&model);
        for m in measured_points() {
            let ideal = chain.ideal(&m);
            let inv = chain.ideal_point_jacobian(&m).try_inverse().unwrap();
            check_jacobian(
                &format!("measured_from_ideal wrt point [{name} {m:?}]"),
                &v2(ideal),
                &[1.0; 2],
                &|x| {
                    v2(chain
                        .measured_from_ideal(&Vector2::new(x[0], x[1]))
                        .unwrap())
                },
                &dyn_mat(&inv),
                REL,
            );
            check_jacobian(
                &format!("measured_from_ideal_to_tolerance wrt point [{name} {m:?}]"),
                &v2(ideal),
                &[1.0; 2],
                &|x| {
                    v2(chain
                        .measured_from_ideal_to_tolerance(&Vector2::new(x[0], x[1]))
                        .unwrap())
                },
                &dyn_mat(&inv),
                REL,
            );
        }
    }
}

#[test]
fn pinhole_and_ray_jacobians() {
    let points = [
        Vector3::new(0.0, 0.0, 900.0),
        Vector3::new(-150.0, 80.0, 700.0),
        Vector3::new(220.0, -310.0, 1400.0),
    ];
    for (name, model) in example_models() {
        let chain = Model::standard(&model);
        for p in points {
            let ideal = chain.ideal_of_point(&p).unwrap();
            // A fresh buffer holds the identity: the pinhole's own Jacobians.
            let mut jac = chain.jacobian_buffer();
            let ab = chain.ray_of_ideal_with_jacobians(&ideal, &mut jac);
            assert_eq!(ab, chain.ray_of_ideal(&ideal));
            // The normalised ray of a projected point is the point's direction.
            assert!((ab - Vector2::new(p.x / p.z, p.y / p.z)).norm() < 1e-14);
            let direction = chain.direction_of_ideal(&ideal).into_inner();
            assert!((direction - p.normalize()).norm() < 1e-14);
            check_jacobian(
                &format!("ray wrt ideal [{name}]"),
                &v2(ideal),
                &[1.0; 2],
                &|x| v2(chain.ray_of_ideal(&Vector2::new(x[0], x[1]))),
                &dyn_mat(&jac.wrt_point),
                REL,
            );
            check_jacobian(
                &format!("ray wrt model, ideal point held [{name}]"),
                &model_vec(&model),
                &MODEL_SCALES,
                &|x| v2(chain_of(x).ray_of_ideal(&ideal)),
                &params_mat(&jac.wrt_params),
                REL,
            );
            check_jacobian(
                &format!("ideal of a sensor-frame point wrt model [{name}]"),
                &model_vec(&model),
                &MODEL_SCALES,
                &|x| v2(chain_of(x).ideal_of_point(&p).unwrap()),
                &DMatrix::from_fn(2, N_PARAMS, |r, c| match (r, c) {
                    (_, 0) => ab[r],
                    (0, 1) | (1, 2) => 1.0,
                    (0, 3) => ab.y,
                    _ => 0.0,
                }),
                REL,
            );
        }
    }
}

#[test]
fn rotation_derivatives_at_every_angle() {
    let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
    let angles = [
        0.0,
        1e-12,
        1e-9,
        1e-5,
        0.05,
        0.0999999,
        0.1,
        0.1000001,
        0.7,
        1.5,
        3.0,
        std::f64::consts::PI - 1e-4,
    ];
    for theta in angles {
        let rvec = axis * theta;
        let pose = Pose::new(rvec, Vector3::zeros());
        let (r, dr) = pose.rotation_with_derivatives();
        assert!((r * r.transpose() - nalgebra::Matrix3::identity()).norm() < 1e-14);
        assert!((r.determinant() - 1.0).abs() < 1e-14);
        let mut analytic = DMatrix::zeros(9, 3);
        for (i, dri) in dr.iter().enumerate() {
            analytic.set_column(i, &DVector::from_column_slice(dri.as_slice()));
        }
        check_jacobian(
            &format!("rotation wrt rvec at θ = {theta}"),
            &DVector::from_row_slice(rvec.as_slice()),
            &[1.0; 3],
            &|x| {
                let r = Pose::new(Vector3::new(x[0], x[1], x[2]), Vector3::zeros()).rotation();
                DVector::from_column_slice(r.as_slice())
            },
            &analytic,
            REL,
        );
    }
}

#[test]
fn transform_jacobians() {
    let p = Vector3::new(-140.0, 90.0, 12.0);
    for pose in example_poses() {
        let (pc, wrt_pose, wrt_p) = pose.transform_with_jacobians(&p);
        assert!((pc - pose.transform(&p)).norm() < 1e-12);
        check_jacobian(
            "transform wrt pose",
            &DVector::from_row_slice(&pose.to_array()),
            &POSE_SCALES,
            &|x| DVector::from_row_slice(pose_of(x).transform(&p).as_slice()),
            &dyn_mat(&wrt_pose),
            REL,
        );
        check_jacobian(
            "transform wrt point",
            &DVector::from_row_slice(p.as_slice()),
            &[1000.0; 3],
            &|x| {
                DVector::from_row_slice(pose.transform(&Vector3::new(x[0], x[1], x[2])).as_slice())
            },
            &dyn_mat(&wrt_p),
            REL,
        );
    }
}

#[test]
fn projection_jacobians() {
    for (name, model) in example_models() {
        let chain = Model::standard(&model);
        let mut jac = chain.jacobian_buffer();
        for (k, pose) in example_poses().into_iter().enumerate() {
            let rotation = pose.rotation_jacobian();
            for xy in example_template_points() {
                let label = format!("[{name} pose {k} {xy:?}]");
                let (pt, j) = chain
                    .project_with_jacobians(&pose, &rotation, &xy, &mut jac)
                    .unwrap();
                assert_eq!(pt, chain.project(&pose, &xy).unwrap());
                let to_tolerance = chain.project_to_tolerance(&pose, &xy).unwrap();
                assert!((pt - to_tolerance).norm() < 1e-12);
                let ideal = chain.project_ideal(&pose, &xy).unwrap();
                assert!((chain.ideal(&pt) - ideal).norm() < 1e-12);
                check_jacobian(
                    &format!("project wrt model {label}"),
                    &model_vec(&model),
                    &MODEL_SCALES,
                    &|x| v2(chain_of(x).project(&pose, &xy).unwrap()),
                    &params_mat(&jac.wrt_params),
                    REL,
                );
                check_jacobian(
                    &format!("project wrt pose {label}"),
                    &DVector::from_row_slice(&pose.to_array()),
                    &POSE_SCALES,
                    &|x| v2(chain.project(&pose_of(x), &xy).unwrap()),
                    &dyn_mat(&j.wrt_pose),
                    REL,
                );
                check_jacobian(
                    &format!("project wrt template {label}"),
                    &v2(xy),
                    &[100.0; 2],
                    &|x| v2(chain.project(&pose, &Vector2::new(x[0], x[1])).unwrap()),
                    &dyn_mat(&j.wrt_point),
                    REL,
                );
            }
        }
    }
}

#[test]
fn back_projection_jacobians() {
    for (name, model) in example_models() {
        let chain = Model::standard(&model);
        let mut jac = chain.jacobian_buffer();
        for (k, pose) in example_poses().into_iter().enumerate() {
            let rotation = pose.rotation_jacobian();
            for xy in example_template_points() {
                let label = format!("[{name} pose {k} {xy:?}]");
                let measured = chain.project(&pose, &xy).unwrap();
                let (back, j) = chain
                    .back_project_with_jacobians(&pose, &rotation, &measured, &mut jac)
                    .unwrap();
                assert!((back - chain.back_project(&pose, &measured).unwrap()).norm() < 1e-12);
                check_jacobian(
                    &format!("back_project wrt model {label}"),
                    &model_vec(&model),
                    &MODEL_SCALES,
                    &|x| v2(chain_of(x).back_project(&pose, &measured).unwrap()),
                    &params_mat(&jac.wrt_params),
                    REL,
                );
                check_jacobian(
                    &format!("back_project wrt pose {label}"),
                    &DVector::from_row_slice(&pose.to_array()),
                    &POSE_SCALES,
                    &|x| v2(chain.back_project(&pose_of(x), &measured).unwrap()),
                    &dyn_mat(&j.wrt_pose),
                    REL,
                );
                check_jacobian(
                    &format!("back_project wrt measured {label}"),
                    &v2(measured),
                    &[1.0; 2],
                    &|x| {
                        v2(chain
                            .back_project(&pose, &Vector2::new(x[0], x[1]))
                            .unwrap())
                    },
                    &dyn_mat(&j.wrt_point),
                    REL,
                );
            }
        }
    }
}

#[test]
fn impact_point_amplitude_jacobian_matches_finite_differences() {
    let geometry = PsdGeometry { lx: 9.0, ly: 7.0 };
    for point in [
        Vector2::new(0.0, 0.0),
        Vector2::new(3.1, -2.2),
        Vector2::new(-4.4, 3.4),
    ] {
        let amps = electrode_currents(&geometry, &point, 2.5);
        let (p, jac) = impact_point_amplitude_jacobian(&geometry, &amps).unwrap();
        assert!((p - point).norm() < 1e-13);
        check_jacobian(
            &format!("impact point wrt amplitudes at {point:?}"),
            &DVector::from_row_slice(&[amps.vx1, amps.vx2, amps.vy1, amps.vy2]),
            &[1.0; 4],
            &|x| {
                let a = Amplitudes {
                    vx1: x[0],
                    vx2: x[1],
                    vy1: x[2],
                    vy2: x[3],
                };
                v2(impact_point(&geometry, &a).unwrap())
            },
            &dyn_mat(&jac),
            REL,
        );
    }
}

#[test]
fn impact_point_gain_jacobian_matches_finite_differences() {
    let geometry = PsdGeometry::default();
    let gains = ChannelGains {
        x2: 1.07,
        y1: 0.94,
        y2: 1.02,
    };
    for point in [
        Vector2::new(0.0, 0.0),
        Vector2::new(3.1, -2.2),
        Vector2::new(-4.4, 4.0),
    ] {
        let amps = electrode_currents(&geometry, &point, 2.5).apply_gains(&gains);
        let (p, jac) = impact_point_gain_jacobian(&geometry, &amps, &gains).unwrap();
        assert!((p - point).norm() < 1e-13);
        check_jacobian(
            &format!("impact point wrt gains at {point:?}"),
            &DVector::from_row_slice(&gains.to_array()),
            &[1.0; 3],
            &|x| {
                let g = ChannelGains {
                    x2: x[0],
                    y1: x[1],
                    y2: x[2],
                };
                v2(impact_point_with_gains(&geometry, &amps, &g).unwrap())
            },
            &dyn_mat(&jac),
            REL,
        );
    }
    // The amplitudes type is plain data: a zero total is refused, not NaN.
    let dark = Amplitudes {
        vx1: 0.0,
        vx2: 0.0,
        vy1: 0.0,
        vy2: 0.0,
    };
    assert!(impact_point_with_gains(&geometry, &dark, &gains).is_err());
}
