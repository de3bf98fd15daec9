//! Acceptance: the paper's sensitivity formula (P40)–(P42) agrees with
//! finite differences of the full model where its small-angle form applies,
//! and the error maps use the full model.

mod support;

use nalgebra::{DMatrix, Vector2};
use psdcal_locate::{
    angle_of_arrival, aoa_deviation, error_map, paper_aoa_error, paper_aoa_error_at,
    paper_sensitivity_focal, paper_sensitivity_point, CalibratedSensor, ErrorSource, LocateOptions,
    MapOptions, Measurement, ParameterCovariance, ParameterErrors,
};
use psdcal_model::{Param, PsdGeometry, SensorModel};

/// (P40) and (P41) are the exact partial derivatives of (P39) for a
/// distortion-free sensor: compare with central differences of the full
/// model (measured point → correction → ray → angle).
#[test]
fn paper_partials_match_finite_differences_of_the_full_model() {
    let mut worst: f64 = 0.0;
    for f in [8.0, 25.0] {
        let model = SensorModel::pinhole(f, 0.0, 0.0);
        for x in [-4.5, -2.0, 0.0, 0.7, 3.0, 4.5] {
            let m = Vector2::new(x, 0.3);
            let alpha = |model: &SensorModel, m: &Vector2<f64>| {
                angle_of_arrival(&psdcal_model::Model::standard(model), m)
                    .unwrap()
                    .alpha
                    .x
            };
            let h = 1e-6;
            let fd_x = (alpha(&model, &(m + Vector2::x() * h))
                - alpha(&model, &(m - Vector2::x() * h)))
                / (2.0 * h);
            let (mut up, mut down) = (model, model);
            up.intrinsics.f += h;
            down.intrinsics.f -= h;
            let fd_f = (alpha(&up, &m) - alpha(&down, &m)) / (2.0 * h);
            let p40 = paper_sensitivity_point(f, x);
            let p41 = paper_sensitivity_focal(f, x);
            assert!(
                (p40 - fd_x).abs() <= 1e-6 * p40.abs(),
                "f {f} x {x}: (P40) {p40} vs {fd_x}"
            );
            let scale = p40.abs(); // ∂α/∂f vanishes at x = 0: compare on the block's scale.
            assert!(
                (p41 - fd_f).abs() <= 1e-6 * scale,
                "f {f} x {x}: (P41) {p41} vs {fd_f}"
            );
            worst = worst
                .max((p40 - fd_x).abs() / p40.abs())
                .max((p41 - fd_f).abs() / scale);
        }
    }
    println!("(P40), (P41) against finite differences: worst relative error {worst:.2e}");
}

/// Small errors of f and of the point (a centre error moves the offset
/// `x − cx` by −Δcx): (P42) equals the full-model |Δα| to first order when
/// both terms push the same way, and bounds it when they do not.
#[test]
fn paper_error_agrees_with_the_full_model_for_small_errors() {
    let mut worst: f64 = 0.0;
    for f in [8.0, 25.0] {
        let model = SensorModel::pinhole(f, 0.5, -0.7);
        for x in [-4.0f64, -1.5, 1.0, 2.5, 4.0] {
            let m = Vector2::new(x, 0.0);
            let offset = x - 0.5;
            // Relative errors of 1e-4: second-order terms are ~1e-4 of the first,
            // so 5e-4 leaves a margin and still catches a wrong partial.
            let df = 1e-4 * f;
            let dcx = 1e-4;
            // α = atan((x − cx)/f): ∂α/∂cx = −f/(f²+x²), ∂α/∂f = −x/(f²+x²).
            // Same sign: Δcx and Δf both lower α where the offset is positive.
            let aligned =
                ParameterErrors::new(vec![(Param::F, df * offset.signum()), (Param::Cx, dcx)])
                    .unwrap();
            let full = aoa_deviation(&model, &aligned, &m, 5000.0)
                .unwrap()
                .alpha_error
                .x
                .abs();
            let paper = paper_aoa_error(f, offset, dcx, df);
            let at = paper_aoa_error_at(&model, &aligned, &m).unwrap().x;
            assert!(
                (at - paper).abs() <= 1e-9 * paper,
                "paper_aoa_error_at {at} vs {paper}"
            );
            let rel = (full - paper).abs() / paper;
            worst = worst.max(rel);
            assert!(
                rel < 5e-4,
                "f {f} x {x}: full {full:e} vs (P42) {paper:e} (rel {rel:e})"
            );
            // Opposite signs: (P42) is an upper bound.
            let opposed =
                ParameterErrors::new(vec![(Param::F, -df * offset.signum()), (Param::Cx, dcx)])
                    .unwrap();
            let full = aoa_deviation(&model, &opposed, &m, 5000.0)
                .unwrap()
                .alpha_error
                .x
                .abs();
            assert!(full <= paper * (1.0 + 5e-4), "bound: {full:e} > {paper:e}");
        }
    }
    println!("(P42) against the full model (relative errors 1e-4): worst gap {worst:.2e}");
}

/// Where the small-angle form does not apply (large errors, strong
/// distortion) the maps still give the full model's error, which the
/// linear form misses.
#[test]
fn maps_use_the_full_model() {
    let model = SensorModel::paper_lens2();
    // Figure-9-like errors, exaggerated: 0.4 mm in f, 0.2 mm in the centre,
    // 20 % in k1.
    let errors =
        ParameterErrors::new(vec![(Param::F, 0.4), (Param::Cx, 0.2), (Param::K1, 2e-3)]).unwrap();
    let options = MapOptions {
        grid: 9,
        distance_mm: 5000.0,
        paper_form: true,
    };
    let map = error_map(
        &model,
        &PsdGeometry::default(),
        &ErrorSource::Parameters(errors.clone()),
        &options,
    )
    .unwrap();
    assert_eq!(map.cells.len(), 81);
    let perturbed = errors.apply(&model);
    let mut largest_gap: f64 = 0.0;
    for cell in &map.cells {
        let v = cell.values.as_ref().unwrap();
        let a = angle_of_arrival(&psdcal_model::Model::standard(&model), &cell.measured).unwrap();
        let b =
            angle_of_arrival(&psdcal_model::Model::standard(&perturbed), &cell.measured).unwrap();
        let expected = (b.alpha - a.alpha).abs();
        assert!((v.aoa_error - expected).abs().max() < 1e-15);
        let expected_pos = ((b.ray_ab - a.ray_ab) * 5000.0).abs();
        assert!((v.position_error - expected_pos).abs().max() < 1e-9);
        let paper = v.paper_aoa_error.unwrap();
        largest_gap = largest_gap.max((paper.x - v.aoa_error.x).abs() / v.aoa_error.x.max(1e-12));
    }
    // The linear form is off by more than 5 % somewhere on the sensor.
    println!("large errors: (P42) differs from the full model by up to {largest_gap:.2}");
    assert!(largest_gap > 0.05, "gap {largest_gap}");
    // Grid layout: row-major, y outer, corners at ±L/2.
    assert_eq!(map.cells[0].measured, Vector2::new(-4.5, -4.5));
    assert_eq!(map.cells[8].measured, Vector2::new(4.5, -4.5));
    assert_eq!(map.cells[80].measured, Vector2::new(4.5, 4.5));
}

/// The k-σ map from a covariance equals k times the propagated σ.
#[test]
fn covariance_map_is_k_sigma() {
    let model = SensorModel::paper_lens1();
    let params = [Param::F, Param::Cx, Param::Cy, Param::K1];
    let sd = [0.05, 0.02, 0.02, 2e-5];
    let mut m = DMatrix::from_fn(4, 4, |i, j| sd[i] * sd[j] * if i == j { 1.0 } else { 0.3 });
    m[(0, 3)] = -0.5 * sd[0] * sd[3];
    m[(3, 0)] = m[(0, 3)];
    let cov = ParameterCovariance::from_params(&params, &m).unwrap();
    let map = error_map(
        &model,
        &PsdGeometry::default(),
        &ErrorSource::Covariance {
            covariance: cov.clone(),
            k: 2.0,
        },
        &MapOptions {
            grid: 5,
            distance_mm: 5000.0,
            paper_form: false,
        },
    )
    .unwrap();
    let sensor = CalibratedSensor::new(model, PsdGeometry::default()).with_covariance(cov);
    for cell in &map.cells {
        let v = cell.values.as_ref().unwrap();
        let est = sensor
            .aoa(
                &Measurement::Point(cell.measured),
                &LocateOptions::default(),
            )
            .unwrap();
        let ca = est.alpha_covariance();
        assert!((v.aoa_error.x - 2.0 * ca[(0, 0)].sqrt()).abs() < 1e-15);
        assert!((v.aoa_error.y - 2.0 * ca[(1, 1)].sqrt()).abs() < 1e-15);
        let cr = est.ray_covariance();
        let pos = 2.0 * 5000.0 * (cr[(0, 0)] + cr[(1, 1)]).sqrt();
        assert!((v.position_error_total - pos).abs() < 1e-9);
    }
}
