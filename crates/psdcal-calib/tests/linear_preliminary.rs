//! The preliminary radial correction (docs/model.md §4.1): line straightness and
//! homography consistency.

mod common;

use nalgebra::Vector2;
use psdcal_calib::homography::{fit_homography, HomographyOptions};
use psdcal_calib::preliminary::{
    estimate_preliminary, Preliminary, PreliminaryOptions, PreliminaryReport,
    PreliminaryTermination,
};
use psdcal_calib::{CalibError, CalibrationData};
use psdcal_model::SensorModel;

use common::{grid, unaligned};

fn run(data: &CalibrationData, method: Preliminary, centre: Vector2<f64>) -> PreliminaryReport {
    estimate_preliminary(
        data,
        &PreliminaryOptions {
            method,
            centre,
            ..Default::default()
        },
    )
    .unwrap()
}

/// RMS over all images of the homography transfer error of the corrected
/// points, mm.
fn homography_rms(data: &CalibrationData, prelim: &PreliminaryReport) -> f64 {
    let corrected = prelim.correct_data(data);
    let mut sum = 0.0;
    for (im, img) in data.images.iter().zip(&corrected) {
        let tpl: Vec<_> = im.points.iter().map(|o| data.template[o.led]).collect();
        let fit = fit_homography(&tpl, img, &HomographyOptions::default()).unwrap();
        sum += fit.rms * fit.rms;
    }
    (sum / data.images.len() as f64).sqrt()
}

#[test]
fn both_methods_find_the_lens_2_distortion_roughly_with_the_centre_at_zero() {
    let truth = SensorModel::paper_lens2();
    for (name, sc, method) in [
        (
            "unaligned",
            unaligned(truth, 31),
            Preliminary::HomographyConsistency,
        ),
        ("grid", grid(truth, 31), Preliminary::Straightness),
    ] {
        let off = PreliminaryReport::off(Vector2::zeros());
        let rep = run(&sc.data, method, Vector2::zeros());
        let (before, after) = (
            homography_rms(&sc.data, &off),
            homography_rms(&sc.data, &rep),
        );
        println!(
            "lens 2, {name}, {method:?}: k1 = {:.4e} (truth 1e-2), k2 = {:.3e} (truth 3e-5), cost {:.3e} -> {:.3e}, \
             {} iterations, {} terms; homography RMS {before:.4e} -> {after:.4e} mm",
            rep.k1, rep.k2, rep.cost_before, rep.cost_after, rep.iterations, rep.terms
        );
        assert_eq!(rep.method, method);
        assert_eq!(rep.termination, PreliminaryTermination::Converged);
        // Rough: the centre is held at (0, 0) while the truth is (0.5, −0.7).
        assert!(rep.k1 > 5e-3 && rep.k1 < 2e-2, "k1 = {:e}", rep.k1);
        // Measured: cost ÷ 14–15, homography RMS ÷ 3.2–3.3 (the rest is the
        // centre offset, see exact_coefficients_with_the_true_centre).
        assert!(rep.cost_after < rep.cost_before / 8.0);
        assert!(
            after < before / 2.5,
            "homography RMS {before:e} -> {after:e}"
        );
    }
}

#[test]
fn lens_1_distortion_is_found_too() {
    let truth = SensorModel::paper_lens1();
    for (sc, method) in [
        (unaligned(truth, 32), Preliminary::HomographyConsistency),
        (grid(truth, 32), Preliminary::Straightness),
    ] {
        let rep = run(&sc.data, method, Vector2::zeros());
        let off = PreliminaryReport::off(Vector2::zeros());
        let (before, after) = (
            homography_rms(&sc.data, &off),
            homography_rms(&sc.data, &rep),
        );
        println!("lens 1, {method:?}: k1 = {:.4e} (truth 2e-3), k2 = {:.3e}, cost {:.3e} -> {:.3e}; homography RMS {before:.4e} -> {after:.4e} mm", rep.k1, rep.k2, rep.cost_before, rep.cost_after);
        assert!(rep.k1 > 1e-3 && rep.k1 < 4e-3, "k1 = {:e}", rep.k1);
        // Measured: homography RMS ÷ 3.6–3.7.
        assert!(
            after < before / 2.5,
            "homography RMS {before:e} -> {after:e}"
        );
        assert!(rep.cost_after < rep.cost_before / 8.0);
    }
}

/// With the correction centred on the true optical centre the model is
/// exact, so noise-free data give back the true coefficients.
#[test]
fn exact_coefficients_with_the_true_centre() {
    let truth = SensorModel::paper_lens2();
    let centre = Vector2::new(0.5, -0.7);
    for (sc, method) in [
        (unaligned(truth, 33), Preliminary::HomographyConsistency),
        (grid(truth, 33), Preliminary::Straightness),
    ] {
        let rep = run(&sc.data, method, centre);
        println!(
            "{method:?} at the true centre: k1 = {:.12e}, k2 = {:.12e}, cost {:.3e}",
            rep.k1, rep.k2, rep.cost_after
        );
        assert!((rep.k1 - 1e-2).abs() < 1e-8 * 1e-2, "k1 = {:e}", rep.k1);
        assert!((rep.k2 - 3e-5).abs() < 1e-6 * 3e-5, "k2 = {:e}", rep.k2);
        assert!(
            rep.cost_after < 1e-16 * rep.cost_before,
            "cost {:e}",
            rep.cost_after
        );
    }
}

#[test]
fn no_distortion_gives_no_correction() {
    let truth = SensorModel::pinhole(8.0, 0.5, -0.7);
    for (sc, method) in [
        (unaligned(truth, 34), Preliminary::HomographyConsistency),
        (grid(truth, 34), Preliminary::Straightness),
    ] {
        let rep = run(&sc.data, method, Vector2::zeros());
        // k1 moves the outermost point (r ≈ 6 mm) by k1·r³: 1e-10 mm² ·216 ≈ 2e-8 mm at most.
        assert!(
            rep.k1.abs() < 1e-10 && rep.k2.abs() < 1e-11,
            "{method:?}: k1 {:e}, k2 {:e}",
            rep.k1,
            rep.k2
        );
    }
}

/// The costs are scale-free: scaling every measured point and the centre by
/// s scales k1 by 1/s² and k2 by 1/s⁴ and leaves the cost unchanged. (A cost
/// that a shrinking correction could lower would fail this.)
#[test]
fn the_scale_is_pinned() {
    let truth = SensorModel::paper_lens2();
    let s = 3.0;
    for (sc, method) in [
        (unaligned(truth, 35), Preliminary::HomographyConsistency),
        (grid(truth, 35), Preliminary::Straightness),
    ] {
        let centre = Vector2::new(0.2, 0.1);
        let a = run(&sc.data, method, centre);
        let mut scaled = sc.data.clone();
        for im in &mut scaled.images {
            for o in &mut im.points {
                o.measured *= s;
            }
        }
        let b = run(&scaled, method, centre * s);
        assert!(
            (b.k1 * s * s - a.k1).abs() < 1e-7 * a.k1.abs(),
            "{method:?}: {:e} vs {:e}",
            b.k1 * s * s,
            a.k1
        );
        assert!(
            (b.k2 * s.powi(4) - a.k2).abs() < 1e-6 * a.k2.abs() + 1e-12,
            "{method:?}: k2"
        );
        assert!(
            (b.cost_after - a.cost_after).abs() < 1e-9 * a.cost_after,
            "{method:?}: cost"
        );
        assert!((b.cost_before - a.cost_before).abs() < 1e-12 * a.cost_before);
    }
}

#[test]
fn method_selection_and_refusals() {
    let truth = SensorModel::paper_lens2();
    let una = unaligned(truth, 36);
    let gri = grid(truth, 36);
    assert_eq!(
        run(&una.data, Preliminary::Auto, Vector2::zeros()).method,
        Preliminary::HomographyConsistency
    );
    assert_eq!(
        run(&gri.data, Preliminary::Auto, Vector2::zeros()).method,
        Preliminary::Straightness
    );
    let off = run(&una.data, Preliminary::Off, Vector2::zeros());
    assert_eq!(
        (off.method, off.k1, off.k2, off.termination),
        (Preliminary::Off, 0.0, 0.0, PreliminaryTermination::NotRun)
    );
    match estimate_preliminary(
        &una.data,
        &PreliminaryOptions {
            method: Preliminary::Straightness,
            ..Default::default()
        },
    ) {
        Err(CalibError::InvalidInput { reason }) => assert!(reason.contains("lines"), "{reason}"),
        other => panic!("expected InvalidInput, got {other:?}"),
    }
    let mut bad = una.data.clone();
    bad.images[0].points[0].led = 99;
    assert!(matches!(
        estimate_preliminary(&bad, &PreliminaryOptions::default()),
        Err(CalibError::UnknownLed { led: 99, .. })
    ));
    let mut nan = una.data.clone();
    nan.images[1].points[2].measured.y = f64::NAN;
    assert!(matches!(
        estimate_preliminary(&nan, &PreliminaryOptions::default()),
        Err(CalibError::InvalidInput { .. })
    ));
}
