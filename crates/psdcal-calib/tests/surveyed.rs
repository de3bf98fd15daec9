//! Calibration from surveyed 3-D points (docs/model.md §8.4): the DLT and
//! its RQ split against known cameras, exact recovery, the 3-D projection's
//! Jacobians against central differences, the survey-inflated covariance
//! against an independent dense computation, and the refusals.

use nalgebra::{DMatrix, Matrix3, Vector2, Vector3};
use psdcal_calib::surveyed::{
    decompose_projection, dense_jacobians, dlt_projection, survey_covariance,
};
use psdcal_calib::{
    calibrate_surveyed, CalibError, ImageObservations, Observation, SurveyedData, SurveyedOptions,
};
use psdcal_model::{Model, Param, Pose, PsdGeometry, SensorModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// A room-like scene: `n` points 1.5–5 m in front of a sensor at
/// `sensor_from_room`, spread over the central 80 % of the field of view.
fn scene(truth: &SensorModel, n: usize, seed: u64) -> (Vec<Vector3<f64>>, Pose) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let pose = Pose::new(
        Vector3::new(
            rng.random_range(-0.5..0.5),
            rng.random_range(-0.5..0.5),
            rng.random_range(-3.0..3.0),
        ),
        Vector3::new(
            rng.random_range(-500.0..500.0),
            rng.random_range(-500.0..500.0),
            rng.random_range(-500.0..500.0),
        ),
    );
    let room_from_sensor = pose.inverse();
    let half = 0.4 * 9.0 / truth.intrinsics.f;
    let points = psdcal_testkit::points_in_view(&room_from_sensor, half, n, &mut rng);
    (points, pose)
}

fn observe(
    truth: &Model,
    points: &[Vector3<f64>],
    poses: &[Pose],
    sigma: f64,
    rng: &mut ChaCha8Rng,
) -> Vec<ImageObservations> {
    poses
        .iter()
        .enumerate()
        .map(|(i, pose)| ImageObservations {
            id: format!("{}", i + 1),
            points: points
                .iter()
                .enumerate()
                .map(|(led, p)| {
                    let e = Vector2::new(rng.sample(StandardNormal), rng.sample(StandardNormal));
                    Observation {
                        led,
                        measured: truth.project_point(pose, p).unwrap() + sigma * e,
                    }
                })
                .collect(),
        })
        .collect()
}

fn data(points: Vec<Vector3<f64>>, images: Vec<ImageObservations>) -> SurveyedData {
    SurveyedData {
        names: (1..=points.len()).map(|k| k.to_string()).collect(),
        points,
        images,
        geometry: PsdGeometry::default(),
    }
}

#[test]
fn dlt_and_rq_recover_a_known_camera() {
    for seed in 0..20 {
        let mut truth = SensorModel::pinhole(8.0 + seed as f64 * 0.7, 0.3, -0.6);
        truth.intrinsics.cx += 0.05 * seed as f64;
        let (points, pose) = scene(&truth, 12, seed);
        let model = Model::standard(&truth);
        let image: Vec<Vector2<f64>> = points
            .iter()
            .map(|p| model.project_point(&pose, p).unwrap())
            .collect();
        let p = dlt_projection(&points, &image).unwrap();
        let (k, est) = decompose_projection(&p).unwrap();
        let f = truth.intrinsics.f;
        assert!((k[(0, 0)] - f).abs() < 1e-7 * f, "seed {seed}: {k}");
        assert!((k[(1, 1)] - f).abs() < 1e-7 * f);
        assert!(k[(0, 1)].abs() < 1e-7 * f);
        assert!((k[(0, 2)] - truth.intrinsics.cx).abs() < 1e-7);
        assert!((k[(1, 2)] - truth.intrinsics.cy).abs() < 1e-7);
        let dr: Matrix3<f64> = est.rotation().transpose() * pose.rotation();
        assert!((dr - Matrix3::identity()).norm() < 1e-8, "seed {seed}");
        assert!((est.t - pose.t).norm() < 1e-6 * pose.t.norm().max(1.0));
    }
}

#[test]
fn noise_free_data_are_fitted_exactly_from_the_dlt_start() {
    for (seed, orientations) in [(1u64, 1usize), (2, 2), (3, 3)] {
        let truth = SensorModel::paper_lens2();
        let (points, pose) = scene(&truth, 20, seed);
        let mut poses = vec![pose];
        for k in 1..orientations {
            let turn = Pose::new(Vector3::new(0.05 * k as f64, -0.04, 0.3), Vector3::zeros());
            poses.push(turn.compose(&pose));
        }
        let model = Model::standard(&truth);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let d = data(points, observe(&model, &[], &[], 0.0, &mut rng));
        let images = observe(&model, &d.points, &poses, 0.0, &mut rng);
        let d = SurveyedData { images, ..d };
        let fit = calibrate_surveyed(&d, &SurveyedOptions::default()).unwrap();
        for p in [Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2] {
            let (est, tru) = (fit.model.get(p.name()).unwrap(), truth.get(p));
            assert!(
                (est - tru).abs() <= 1e-6 * tru.abs().max(1e-3),
                "{}: {est} vs {tru}",
                p.name()
            );
        }
        assert!(fit.rms_image_mm < 1e-9);
        assert_eq!(fit.poses.len(), orientations);
    }
}

#[test]
fn projection_jacobians_match_central_differences() {
    let truth = SensorModel::paper_lens2();
    let model = Model::standard(&truth);
    let (points, pose) = scene(&truth, 5, 7);
    for p in &points {
        let mut jac = model.jacobian_buffer();
        let (m, j) = model
            .project_point_with_jacobians(&pose, &pose.rotation_jacobian(), p, &mut jac)
            .unwrap();
        assert!((m - model.project_point(&pose, p).unwrap()).norm() < 1e-12);
        for k in 0..3 {
            let h = 1e-3;
            let mut a = *p;
            let mut b = *p;
            a[k] += h;
            b[k] -= h;
            let fd = (model.project_point(&pose, &a).unwrap()
                - model.project_point(&pose, &b).unwrap())
                / (2.0 * h);
            assert!((fd - j.wrt_point.column(k)).norm() < 1e-9, "point {k}");
        }
        for k in 0..6 {
            let h = if k < 3 { 1e-6 } else { 1e-3 };
            let shifted = |s: f64| {
                let mut arr = pose.to_array();
                arr[k] += s;
                model.project_point(&Pose::from_array(&arr), p).unwrap()
            };
            let fd = (shifted(h) - shifted(-h)) / (2.0 * h);
            let analytic = j.wrt_pose.column(k);
            assert!(
                (fd - analytic).norm() < 1e-6 * analytic.norm().max(1e-3),
                "pose {k}"
            );
        }
        for name in ["f", "cx", "cy", "k1", "k2"] {
            let c = model.index(name).unwrap();
            let h = 1e-6 * model.get(name).unwrap().abs().max(1e-3);
            let shifted = |s: f64| {
                let mut m2 = model.clone();
                m2.set(name, model.get(name).unwrap() + s).unwrap();
                m2.project_point(&pose, p).unwrap()
            };
            let fd = (shifted(h) - shifted(-h)) / (2.0 * h);
            let analytic = jac.column(c);
            assert!(
                (fd - analytic).norm() < 1e-5 * analytic.norm().max(1e-6),
                "{name}: {fd} vs {analytic}"
            );
        }
    }
}

#[test]
fn survey_covariance_matches_a_dense_recomputation() {
    let truth = SensorModel::paper_lens2();
    let (points, pose) = scene(&truth, 18, 11);
    let model = Model::standard(&truth);
    let turn = Pose::new(Vector3::new(0.06, 0.02, -0.2), Vector3::zeros());
    let poses = vec![pose, turn.compose(&pose)];
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let images = observe(&model, &points, &poses, 0.0, &mut rng);
    let d = data(points.clone(), images);
    let free = [Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2];
    let state = psdcal_calib::surveyed::SurveyedState {
        model: model.clone(),
        poses: poses.clone(),
    };
    let (j, _, jp) = dense_jacobians(&d, &state, &free).unwrap();
    let (sigma_s, cost) = (2.0, 1e-4);
    let (cov, sm2, share) = survey_covariance(&j, cost, &jp, points.len(), sigma_s).unwrap();
    // Independent: the whole J_P (2n × 3N), Σ = σ_m² I + σ_s² J_P J_Pᵀ, the
    // sandwich S⁻¹ Jᵀ Σ J S⁻¹ and the residual-maker's trace tr((I − H) J_P J_Pᵀ).
    let rows = j.nrows();
    let mut big_jp = DMatrix::<f64>::zeros(rows, 3 * points.len());
    for (obs, (pt, dp)) in jp.iter().enumerate() {
        for r in 0..2 {
            for c in 0..3 {
                big_jp[(2 * obs + r, 3 * pt + c)] = dp[(r, c)];
            }
        }
    }
    let s_inv = (j.transpose() * &j).try_inverse().unwrap();
    let h = &j * &s_inv * j.transpose();
    let resid_maker = DMatrix::<f64>::identity(rows, rows) - h;
    let t = (&resid_maker * &big_jp * big_jp.transpose()).trace();
    let dof = (rows - j.ncols()) as f64;
    let expected_sm2 = ((cost - sigma_s * sigma_s * t) / dof).max(0.0);
    assert!((share - sigma_s * sigma_s * t).abs() < 1e-9 * share.abs().max(1e-30));
    assert!((sm2 - expected_sm2).abs() <= 1e-9 * expected_sm2.max(1e-30));
    let sigma = DMatrix::<f64>::identity(rows, rows) * expected_sm2
        + &big_jp * big_jp.transpose() * (sigma_s * sigma_s);
    let expected = &s_inv * j.transpose() * sigma * &j * &s_inv;
    let scale = expected.diagonal().map(f64::sqrt);
    for a in 0..cov.nrows() {
        for b in 0..cov.ncols() {
            let rel = (cov[(a, b)] - expected[(a, b)]) / (scale[a] * scale[b]);
            assert!(rel.abs() < 1e-8, "({a}, {b}): {rel}");
        }
    }
}

#[test]
fn coplanar_points_in_one_image_are_refused_with_what_to_change() {
    let truth = SensorModel::paper_lens2();
    let model = Model::standard(&truth);
    let pose = Pose::new(Vector3::new(0.2, -0.1, 0.0), Vector3::new(0.0, 0.0, 3000.0));
    let points: Vec<Vector3<f64>> = (0..16)
        .map(|k| {
            Vector3::new(
                -600.0 + 80.0 * k as f64,
                -400.0 + 50.0 * ((k * 7) % 16) as f64,
                0.0,
            )
        })
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let images = observe(&model, &points, &[pose], 0.0, &mut rng);
    let e = calibrate_surveyed(&data(points, images), &SurveyedOptions::default()).unwrap_err();
    let text = e.to_string();
    assert!(matches!(e, CalibError::Degenerate { .. }), "{text}");
    assert!(
        text.contains("coplanar") && text.contains("different depths"),
        "{text}"
    );
}

#[test]
fn too_few_points_are_refused_with_the_minimum() {
    let truth = SensorModel::paper_lens2();
    let model = Model::standard(&truth);
    let (points, pose) = scene(&truth, 5, 9);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let images = observe(&model, &points, &[pose], 0.0, &mut rng);
    let e = calibrate_surveyed(&data(points, images), &SurveyedOptions::default()).unwrap_err();
    let text = e.to_string();
    assert!(
        text.contains("sees 5") && text.contains("at least 6"),
        "{text}"
    );
    let bad = SurveyedOptions {
        survey_sigma_mm: -1.0,
        ..SurveyedOptions::default()
    };
    let (points, pose) = scene(&truth, 8, 9);
    let images = observe(&model, &points, &[pose], 0.0, &mut rng);
    assert!(calibrate_surveyed(&data(points, images), &bad).is_err());
}
