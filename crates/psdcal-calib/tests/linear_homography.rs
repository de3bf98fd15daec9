//! Homographies by DLT (P17)–(P18) with and without Hartley normalisation
//! (P36)–(P38).

mod common;

use nalgebra::{Matrix3, Vector2};
use psdcal_calib::homography::{
    fit_homography, normalizing_transform, Homography, HomographyOptions,
};
use psdcal_calib::CalibError;
use psdcal_model::{Pose, SensorModel};

use common::{observe, poses, unaligned_template};

/// `A [r1 r2 t]`, the exact homography of a pinhole and a pose.
fn true_homography(model: &SensorModel, pose: &Pose) -> Homography {
    let k = &model.intrinsics;
    let a = Matrix3::new(k.f, 0.0, k.cx, 0.0, k.f, k.cy, 0.0, 0.0, 1.0);
    let r = pose.rotation();
    let m = Matrix3::from_columns(&[r.column(0).into_owned(), r.column(1).into_owned(), pose.t]);
    Homography::from_matrix(a * m).unwrap()
}

fn pairs(data: &psdcal_calib::CalibrationData, i: usize) -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
    let im = &data.images[i];
    (
        im.points.iter().map(|o| data.template[o.led]).collect(),
        im.points.iter().map(|o| o.measured).collect(),
    )
}

#[test]
fn exact_on_noise_free_pinhole_points_with_and_without_normalisation() {
    let template = unaligned_template();
    for f in [8.0, 25.0] {
        let model = SensorModel::pinhole(f, 0.5, -0.7);
        let poses = poses(&model, &template, 9, 30f64.to_radians(), 7);
        let data = observe(&model, &template, &[], &poses, true, 0.0, 0);
        for (i, pose) in poses.iter().enumerate() {
            let truth = true_homography(&model, pose);
            let (tpl, img) = pairs(&data, i);
            for normalize in [true, false] {
                let fit = fit_homography(&tpl, &img, &HomographyOptions { normalize }).unwrap();
                let h = fit.homography.matrix();
                // Both have unit norm and H[(2,2)] > 0, so they are directly comparable.
                let err = (h - truth.matrix()).norm();
                assert!(
                    err < 1e-9,
                    "f = {f}, image {i}, normalize = {normalize}: ‖ΔH‖ = {err:.3e}"
                );
                assert!((h.norm() - 1.0).abs() < 1e-14 && h[(2, 2)] > 0.0);
                assert!(fit.rms < 1e-9, "rms {:.3e}", fit.rms);
                assert_eq!((fit.points, fit.normalized), (14, normalize));
                assert!(
                    fit.conditioning > 1e-6,
                    "conditioning {:.3e}",
                    fit.conditioning
                );
            }
        }
    }
}

#[test]
fn transfer_error_matches_the_noise_level() {
    // 14 points, 8 homography parameters: E[Σ‖e‖²] ≈ σ² (2m − 8), so the
    // RMS per point is ≈ σ √((2m − 8)/m) = 1.195 σ; allow 0.6–1.5× that for
    // one draw (28 residuals, 20 degrees of freedom).
    let template = unaligned_template();
    let model = SensorModel::pinhole(8.0, 0.5, -0.7);
    let poses = poses(&model, &template, 9, 30f64.to_radians(), 8);
    let sigma = 1e-3;
    let data = observe(&model, &template, &[], &poses, true, sigma, 99);
    let expected = sigma * (20.0f64 / 14.0).sqrt();
    let mut mean_square = 0.0;
    for i in 0..poses.len() {
        let (tpl, img) = pairs(&data, i);
        let fit = fit_homography(&tpl, &img, &HomographyOptions::default()).unwrap();
        assert!(
            fit.rms > 0.3 * expected && fit.rms < 2.5 * expected,
            "image {i}: rms {:.3e}",
            fit.rms
        );
        mean_square += fit.rms * fit.rms / poses.len() as f64;
    }
    let rms = mean_square.sqrt();
    assert!(
        rms > 0.6 * expected && rms < 1.5 * expected,
        "pooled rms {rms:.3e} vs expected {expected:.3e}"
    );
}

#[test]
fn apply_matches_projection_and_normalisation_is_hartleys() {
    let template = unaligned_template();
    let model = SensorModel::pinhole(8.0, 0.5, -0.7);
    let pose = poses(&model, &template, 1, 30f64.to_radians(), 3)[0];
    let h = true_homography(&model, &pose);
    let chain = psdcal_model::Model::standard(&model);
    for p in &template {
        let q = chain.project_ideal(&pose, p).unwrap();
        assert!((h.apply(p).unwrap() - q).norm() < 1e-12);
    }
    let t = normalizing_transform(&template).unwrap();
    let moved: Vec<Vector2<f64>> = template.iter().map(|p| (t * p.push(1.0)).xy()).collect();
    let centroid = moved.iter().sum::<Vector2<f64>>() / moved.len() as f64;
    let mean_dist = moved.iter().map(|p| p.norm()).sum::<f64>() / moved.len() as f64;
    assert!(centroid.norm() < 1e-14);
    assert!((mean_dist - 2f64.sqrt()).abs() < 1e-14);
}

#[test]
fn three_points_are_too_few() {
    let tpl = [
        Vector2::new(0.0, 0.0),
        Vector2::new(1.0, 0.0),
        Vector2::new(0.0, 1.0),
    ];
    let img = [
        Vector2::new(0.1, 0.0),
        Vector2::new(1.0, 0.2),
        Vector2::new(0.0, 1.3),
    ];
    match fit_homography(&tpl, &img, &HomographyOptions::default()) {
        Err(CalibError::TooFewPoints { points: 3, .. }) => {}
        other => panic!("expected TooFewPoints, got {other:?}"),
    }
}

#[test]
fn collinear_and_rank_deficient_configurations_are_refused() {
    // All template points on one line.
    let tpl: Vec<_> = (0..6)
        .map(|i| Vector2::new(10.0 * i as f64, 5.0 * i as f64 - 3.0))
        .collect();
    let img: Vec<_> = (0..6)
        .map(|i| Vector2::new(0.3 * i as f64, 0.1 * (i * i) as f64))
        .collect();
    for normalize in [true, false] {
        match fit_homography(&tpl, &img, &HomographyOptions { normalize }) {
            Err(CalibError::Degenerate { reason }) => {
                assert!(reason.contains("collinear"), "{reason}")
            }
            other => panic!("expected Degenerate, got {other:?}"),
        }
    }
    // Image points on one line (template seen edge-on).
    let tpl2 = [
        Vector2::new(0.0, 0.0),
        Vector2::new(1.0, 0.0),
        Vector2::new(0.0, 1.0),
        Vector2::new(1.0, 1.0),
    ];
    let img2 = [
        Vector2::new(0.0, 0.0),
        Vector2::new(1.0, 1.0),
        Vector2::new(2.0, 2.0),
        Vector2::new(3.0, 3.0),
    ];
    assert!(matches!(
        fit_homography(&tpl2, &img2, &HomographyOptions::default()),
        Err(CalibError::Degenerate { .. })
    ));
    // Four points, three of them collinear: not collinear as a set, but no
    // regular homography exists. With the three image points collinear too,
    // the DLT system is rank deficient (a family of solutions) ...
    let tpl3 = [
        Vector2::new(0.0, 0.0),
        Vector2::new(1.0, 0.0),
        Vector2::new(2.0, 0.0),
        Vector2::new(0.5, 1.0),
    ];
    let img3 = [
        Vector2::new(0.0, 0.0),
        Vector2::new(1.1, 0.1),
        Vector2::new(2.2, 0.2),
        Vector2::new(0.4, 0.9),
    ];
    match fit_homography(&tpl3, &img3, &HomographyOptions::default()) {
        Err(CalibError::Degenerate { reason }) => {
            assert!(reason.contains("not determined"), "{reason}")
        }
        other => panic!("expected Degenerate, got {other:?}"),
    }
    // ... and with them not collinear the unique solution is singular.
    let img4 = [
        Vector2::new(0.0, 0.0),
        Vector2::new(1.1, 0.1),
        Vector2::new(2.3, 0.1),
        Vector2::new(0.4, 0.9),
    ];
    match fit_homography(&tpl3, &img4, &HomographyOptions::default()) {
        Err(CalibError::Degenerate { reason }) => assert!(reason.contains("singular"), "{reason}"),
        other => panic!("expected Degenerate, got {other:?}"),
    }
}

#[test]
fn bad_inputs_give_typed_errors_not_nan() {
    let tpl = [
        Vector2::new(0.0, 0.0),
        Vector2::new(1.0, 0.0),
        Vector2::new(0.0, 1.0),
        Vector2::new(1.0, 1.0),
    ];
    let mut img = tpl;
    img[2].x = f64::NAN;
    assert!(matches!(
        fit_homography(&tpl, &img, &HomographyOptions::default()),
        Err(CalibError::InvalidInput { .. })
    ));
    assert!(matches!(
        fit_homography(&tpl, &tpl[..3], &HomographyOptions::default()),
        Err(CalibError::InvalidInput { .. })
    ));
    assert!(Homography::from_matrix(Matrix3::zeros()).is_err());
    assert!(
        Homography::from_matrix(Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0)).is_err()
    );
    // A point on the vanishing line maps to infinity.
    let h =
        Homography::from_matrix(Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0)).unwrap();
    assert!(h.apply(&Vector2::new(-1.0, 5.0)).is_err());
}
