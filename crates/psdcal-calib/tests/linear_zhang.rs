//! The corrected closed form (P19)–(P25) and the extrinsics (P26)–(P28).

mod common;

use nalgebra::{Matrix3, Vector2};
use psdcal_calib::homography::{fit_homography, Homography, HomographyOptions};
use psdcal_calib::zhang::{closed_form, closed_form_intrinsics, pose_from_homography};
use psdcal_calib::{CalibError, CalibrationData};
use psdcal_model::{Pose, SensorModel};

use common::{observe, poses, unaligned_template};

fn homographies(data: &CalibrationData, normalize: bool) -> Vec<Homography> {
    data.images
        .iter()
        .map(|im| {
            let tpl: Vec<Vector2<f64>> = im.points.iter().map(|o| data.template[o.led]).collect();
            let img: Vec<Vector2<f64>> = im.points.iter().map(|o| o.measured).collect();
            fit_homography(&tpl, &img, &HomographyOptions { normalize })
                .unwrap()
                .homography
        })
        .collect()
}

#[test]
fn closed_form_and_extrinsics_are_exact_on_pinhole_data() {
    let template = unaligned_template();
    for (f, seed) in [(8.0, 21), (25.0, 22)] {
        let truth = SensorModel::pinhole(f, 0.5, -0.7);
        let true_poses = poses(&truth, &template, 9, 30f64.to_radians(), seed);
        let data = observe(&truth, &template, &[], &true_poses, true, 0.0, 0);
        for normalize in [true, false] {
            let homs = homographies(&data, normalize);
            let sol = closed_form(&homs).unwrap();
            let fe = sol.focal_length().unwrap();
            println!(
                "f = {f}, normalize = {normalize}: f {fe:.12} cx {:.12} cy {:.12} (passes {}, singular values {:?})",
                sol.cx, sol.cy, sol.passes, sol.singular_values
            );
            assert!((fe - f).abs() < 1e-8 * f, "f {fe} vs {f}");
            assert!(
                (sol.cx - 0.5).abs() < 1e-8 && (sol.cy + 0.7).abs() < 1e-8,
                "c ({}, {})",
                sol.cx,
                sol.cy
            );
            assert_eq!(sol.passes, 2);
            assert!(
                sol.uniqueness() > 1e-6,
                "uniqueness {:.3e}",
                sol.uniqueness()
            );
            // b ∝ (1/f², −cx/f², −cy/f², (cx² + cy² + f²)/f²), unit norm.
            let b = [1.0, -0.5, 0.7, 0.5f64.powi(2) + 0.7f64.powi(2) + f * f];
            let nb = b.iter().map(|v| v * v).sum::<f64>().sqrt();
            for (k, (est, exact)) in sol.b.iter().zip(b).enumerate() {
                assert!(
                    (est - exact / nb).abs() < 1e-9,
                    "b[{k}] {est} vs {}",
                    exact / nb
                );
            }
            let model = closed_form_intrinsics(&homs).unwrap();
            assert_eq!(model.intrinsics.f, fe);
            // Extrinsics from the estimated intrinsics.
            for (h, pose) in homs.iter().zip(&true_poses) {
                let est = pose_from_homography(h, fe, sol.cx, sol.cy).unwrap();
                let dr = (est.rotation() - pose.rotation()).norm();
                let dt = (est.t - pose.t).norm() / pose.t.norm();
                assert!(
                    dr < 1e-8 && dt < 1e-8,
                    "f = {f}: ΔR {dr:.3e}, Δt/t {dt:.3e}"
                );
                assert!((est.rvec - pose.rvec).norm() < 1e-8);
            }
        }
    }
}

#[test]
fn pose_handles_a_negative_homography_scale_and_returns_a_rotation() {
    let truth = SensorModel::pinhole(8.0, 0.5, -0.7);
    let template = unaligned_template();
    let pose = poses(&truth, &template, 1, 30f64.to_radians(), 5)[0];
    let k = &truth.intrinsics;
    let a = Matrix3::new(k.f, 0.0, k.cx, 0.0, k.f, k.cy, 0.0, 0.0, 1.0);
    let r = pose.rotation();
    let m = Matrix3::from_columns(&[r.column(0).into_owned(), r.column(1).into_owned(), pose.t]);
    // The matrix is normalised to H[(2,2)] > 0 on construction, so the sign
    // is fixed by t_z > 0 either way; a perturbed H must still give a rotation.
    let mut noisy = a * m * -3.0;
    noisy[(0, 1)] *= 1.01;
    let est =
        pose_from_homography(&Homography::from_matrix(noisy).unwrap(), k.f, k.cx, k.cy).unwrap();
    let rot = est.rotation();
    assert!((rot.transpose() * rot - Matrix3::identity()).norm() < 1e-12);
    assert!((rot.determinant() - 1.0).abs() < 1e-12);
    assert!(est.t.z > 0.0);
    assert!(
        (est.rotation() - r).norm() < 0.05,
        "close to the truth despite the perturbation"
    );
    assert!(matches!(
        pose_from_homography(&Homography::from_matrix(a * m).unwrap(), f64::NAN, 0.0, 0.0),
        Err(CalibError::InvalidInput { .. })
    ));
}

/// Homographies whose constraints are satisfied by `B = diag(1, 1, −1)`
/// (columns of Lorentz boosts): the closed form must return `f² = −1 mm²`
/// and refuse it with a typed error.
#[test]
fn non_positive_f_squared_is_a_typed_error() {
    let boost = |a: f64, phi: f64| {
        let (c, s, ch, sh) = (phi.cos(), phi.sin(), a.cosh(), a.sinh());
        Matrix3::new(
            1.0 + (ch - 1.0) * c * c,
            (ch - 1.0) * c * s,
            sh * c,
            (ch - 1.0) * c * s,
            1.0 + (ch - 1.0) * s * s,
            sh * s,
            sh * c,
            sh * s,
            ch,
        )
    };
    let homs: Vec<_> = [(0.3, 0.0), (0.5, 1.2), (0.2, 2.5), (0.4, 4.0)]
        .iter()
        .map(|&(a, phi)| Homography::from_matrix(boost(a, phi)).unwrap())
        .collect();
    let sol = closed_form(&homs).unwrap();
    assert!((sol.f_squared + 1.0).abs() < 1e-9, "f² = {}", sol.f_squared);
    assert!(sol.cx.abs() < 1e-9 && sol.cy.abs() < 1e-9);
    match sol.focal_length() {
        Err(CalibError::NonPositiveFocalSquared { f_squared }) => {
            assert!((f_squared + 1.0).abs() < 1e-9)
        }
        other => panic!("expected NonPositiveFocalSquared, got {other:?}"),
    }
    assert!(matches!(
        closed_form_intrinsics(&homs),
        Err(CalibError::NonPositiveFocalSquared { .. })
    ));
}

#[test]
fn fronto_parallel_poses_and_too_few_homographies_are_refused() {
    let template = unaligned_template();
    let truth = SensorModel::pinhole(8.0, 0.5, -0.7);
    let flat = poses(&truth, &template, 9, 0.0, 4);
    assert!(flat.iter().all(|p: &Pose| p.rvec.norm() == 0.0));
    let data = observe(&truth, &template, &[], &flat, true, 0.0, 0);
    let homs = homographies(&data, true);
    match closed_form(&homs) {
        Err(CalibError::Degenerate { reason }) => assert!(reason.contains("parallel"), "{reason}"),
        other => panic!("expected Degenerate, got {other:?}"),
    }
    assert!(matches!(
        closed_form(&homs[..1]),
        Err(CalibError::TooFewImages {
            usable: 1,
            needed: 2
        })
    ));
    // Two tilted images suffice for the 3 degrees of freedom of b.
    let tilted = poses(&truth, &template, 2, 30f64.to_radians(), 4);
    let data = observe(&truth, &template, &[], &tilted, true, 0.0, 0);
    let f = closed_form(&homographies(&data, true))
        .unwrap()
        .focal_length()
        .unwrap();
    assert!((f - 8.0).abs() < 1e-8, "f = {f}");
}
