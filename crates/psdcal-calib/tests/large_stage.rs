//! A stage with a large parameter block runs through calibration end to end
//! (issue "One engine"): psdcal-testkit's test-only `PolyField(10, 4.5)` (a
//! polynomial displacement field, 200 coefficients) placed FIRST in the
//! chain, acting on the measured point, before the paper's lens 2 (f 8 mm,
//! k1 1e-2, k2 3e-5, centre (0.5, −0.7)). The data are 12 images of the
//! 14-LED template, projected through the whole chain (`Model::project`),
//! noise-free or with a point noise of 1 µm per coordinate.
//!
//! - (a) with the stage held fixed at its true coefficients, `calibrate`
//!   recovers f, cx, cy, k1, k2 exactly (noise-free);
//! - (b) calibrating the same data without the stage fits clearly worse
//!   (the stage matters);
//! - (c) `refine` with the field's 20 highest-order coefficients freed (from
//!   0) besides f, cx, cy, k1, k2 converges and recovers every freed value
//!   within 4σ of the reported covariance at 1 µm noise;
//! - (d) the covariance has one row per freed name, in
//!   `RefineOptions::free_names()` order.

mod support;

use nalgebra::Vector2;
use psdcal_calib::{
    calibrate, covariance, refine, CalibrateOptions, CalibrationData, RefineOptions,
};
use psdcal_model::{Model, Param, Pose, SensorModel, Stage};
use psdcal_testkit::PolyField;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::Normal;

/// Polynomial order per axis (10 × 10 monomials, 200 coefficients) and the
/// half-side of the square it is normalised on, mm.
const POLY_N: usize = 10;
const POLY_HALF_MM: f64 = 4.5;
const IMAGES: usize = 12;
/// Point noise per coordinate at the noisy level, mm (1 µm).
const SIGMA_MM: f64 = 1e-3;
const SEED: u64 = 12;
/// The standard parameters the calibration frees (its default).
const STANDARD: [Param; 5] = [Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2];

fn poly() -> PolyField {
    PolyField::new(POLY_N, POLY_HALF_MM)
}

/// The true chain: PolyField (first) → PSD radial (l1 = 0) → lens 2 →
/// pinhole, the field at its second example block (a smooth field of a few
/// µm: 6.4 µm constant in x, decaying with the order).
fn truth() -> Model {
    let stage = poly();
    let block = stage.example_parameters()[1].clone();
    let mut model = Model::standard(&SensorModel::paper_lens2())
        .with_stage(0, Box::new(stage.clone()))
        .unwrap();
    for (p, v) in stage.parameters().iter().zip(&block) {
        model.set(&p.name, *v).unwrap();
    }
    assert_eq!(model.stage_kinds()[0], "test_poly_field");
    assert_eq!(model.len(), 211);
    model
}

/// The field's coefficient names of total order `i + j ≥ 15` (10 per axis:
/// orders 15 to 18), highest order first and y before x — deliberately not
/// the model's column order, so that (d) sees the order of the request.
fn highest_order_names() -> Vec<String> {
    let mut names = Vec::new();
    for order in (15..=2 * (POLY_N - 1)).rev() {
        for axis in ["y", "x"] {
            for i in (0..POLY_N).rev() {
                let Some(j) = order.checked_sub(i).filter(|j| *j < POLY_N) else {
                    continue;
                };
                names.push(format!("poly_{axis}_{i}_{j}"));
            }
        }
    }
    assert_eq!(names.len(), 20);
    names
}

struct Scene {
    poses: Vec<Pose>,
    exact: CalibrationData,
    noisy: CalibrationData,
}

/// 12 poses of psdcal-testkit's covering draw (drawn for lens 2 alone: the
/// field moves the points by a few µm only, well inside the ±4.4 mm margin
/// to the sensor's edge), the measured points through the whole chain, and
/// the same points with N(0, 1 µm) per coordinate.
fn scene(model: &Model) -> Scene {
    let template = support::template(14);
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let poses = support::poses_for(&SensorModel::paper_lens2(), &template, IMAGES, &mut rng);
    let points: Vec<Vec<Vector2<f64>>> = poses
        .iter()
        .map(|pose| {
            template
                .iter()
                .map(|xy| model.project(pose, xy).expect("projectable"))
                .collect()
        })
        .collect();
    let mut noisy_points = points.clone();
    let noise = Normal::new(0.0, SIGMA_MM).unwrap();
    psdcal_testkit::add_noise(&mut noisy_points, &noise, &mut rng);
    Scene {
        poses,
        exact: support::calibration_data(&template, &[], points),
        noisy: support::calibration_data(&template, &[], noisy_points),
    }
}

#[test]
fn a_fixed_large_stage_is_carried_through_calibrate_exactly() {
    let truth = truth();
    let s = scene(&truth);
    // The start's f, cx, cy, k1, k2 come from the initialisation (which
    // ignores the stage); `base` supplies the stage and its 200 fixed values.
    let options = CalibrateOptions {
        base: truth.clone(),
        ..CalibrateOptions::default()
    };
    let r = calibrate(&s.exact, &options).unwrap();
    assert!(
        r.refine.termination.converged(),
        "{:?}",
        r.refine.termination
    );
    // Noise-free: the fit is exact down to the solver's exact-fit floor.
    assert!(
        r.statistics.residual_mm2 <= exact_floor_mm2(&s.exact),
        "residual {:e} mm²",
        r.statistics.residual_mm2
    );
    // Relative 1e-6 (the brief; the same bound as tests/calibrate.rs).
    for p in STANDARD {
        let (got, want) = (r.model.get(p.name()).unwrap(), truth.get(p.name()).unwrap());
        assert!(
            (got - want).abs() <= 1e-6 * want.abs(),
            "{p}: {got:e}, truth {want:e}"
        );
    }
    // The fixed block is untouched.
    assert_eq!(
        r.model.values()[11..],
        truth.values()[11..],
        "fixed coefficients"
    );
    assert_eq!(r.model.stage_kinds(), truth.stage_kinds());
}

/// Exact-fit floor of the refinement: RMS 1e-10 mm per point (template
/// plane), i.e. a residual of `points × 1e-20` mm² (psdcal-calib's
/// `EXACT_FIT_MS`, a few hundred times the rounding of a back-projection).
fn exact_floor_mm2(data: &CalibrationData) -> f64 {
    1e-20 * data.point_count() as f64
}

/// Whether `got` matches `truth` in f, cx, cy, k1, k2 to (a)'s relative 1e-6.
fn standard_recovered(got: &Model, truth: &Model) -> bool {
    STANDARD.iter().all(|p| {
        let (g, t) = (got.get(p.name()).unwrap(), truth.get(p.name()).unwrap());
        (g - t).abs() <= 1e-6 * t.abs()
    })
}

#[test]
fn calibrating_without_the_stage_fits_clearly_worse() {
    // Noise-free, so that the comparison is between models, not noise
    // draws: with the stage the fit reaches the exact-fit floor; without it
    // the part of the field that f, cx, cy, k1, k2 and the poses cannot
    // absorb remains. (That part is small: 0.08 µm RMS on the sensor for
    // this field, most of whose 6.4 µm is a constant offset that cx, cy
    // absorb; at 1 µm point noise the two fits' σ̂² differ by 0.4 %, well
    // inside the χ² spread √(2/dof) ≈ 9 %, so a noisy comparison would
    // need a larger field.)
    let truth = truth();
    let s = scene(&truth);
    let with = CalibrateOptions {
        base: truth.clone(),
        ..CalibrateOptions::default()
    };
    let a = calibrate(&s.exact, &with).unwrap();
    let b = calibrate(&s.exact, &CalibrateOptions::default()).unwrap();
    let floor = exact_floor_mm2(&s.exact);
    assert!(
        a.statistics.residual_mm2 <= floor,
        "with the stage: {:e} mm²",
        a.statistics.residual_mm2
    );
    // "Clearly worse": above the exact-fit floor by more than the rounding
    // it allows for (RMS 1e3 times the floor's, i.e. the residual 1e6 times
    // it): a genuine model error, not rounding.
    assert!(
        b.statistics.residual_mm2 > 1e6 * floor,
        "without the stage: {:e} mm² (floor {floor:e})",
        b.statistics.residual_mm2
    );
    // And the parameters are biased: (a)'s recovery fails without the stage.
    assert!(standard_recovered(&a.model, &truth));
    assert!(
        !standard_recovered(&b.model, &truth),
        "without the stage: {:?}",
        b.model.sensor_model()
    );
}

#[test]
fn refine_frees_part_of_the_large_block_with_consistent_covariance() {
    let truth = truth();
    let s = scene(&truth);
    let stage_names = highest_order_names();
    let options = RefineOptions {
        free: STANDARD.to_vec(),
        free_stage_parameters: stage_names.clone(),
        ..RefineOptions::default()
    };
    // Start: the standard values and poses disturbed as in the refinement
    // tests (f × 1.04, centre off by (0.15, −0.2) mm, k1 × 0.8, k2 = 0, poses
    // turned and moved), the 20 freed coefficients at 0, the other 180 at
    // their true values.
    let (start_sensor, start_poses) = psdcal_testkit::perturbed(&truth.sensor_model(), &s.poses);
    let mut start = truth.clone();
    for p in STANDARD {
        start.set(p.name(), start_sensor.get(p)).unwrap();
    }
    for name in &stage_names {
        start.set(name, 0.0).unwrap();
    }
    let mut noise_free_errors = Vec::new();
    for (label, data, noisy) in [("noise-free", &s.exact, false), ("1 µm", &s.noisy, true)] {
        let r = refine(data, start.clone(), &start_poses, &options).unwrap();
        assert!(
            r.report.termination.converged(),
            "{label}: {:?} after {} iterations",
            r.report.termination,
            r.report.iterations
        );
        let cov = covariance(data, &r, &options).unwrap();
        // (d) one row per freed name, in free_names() order.
        assert_eq!(cov.names(), options.free_names(), "{label}");
        assert_eq!(cov.matrix().nrows(), 25);
        assert_eq!(cov.matrix().ncols(), 25);
        if !noisy {
            // Noise-free: exact fit; the errors are checked against the
            // noisy fit's σ below.
            assert!(
                r.cost <= exact_floor_mm2(data),
                "{label}: cost {:e}",
                r.cost
            );
            noise_free_errors = cov
                .names()
                .iter()
                .map(|n| r.model.get(n).unwrap() - truth.get(n).unwrap())
                .collect();
            continue;
        }
        // At 1 µm: every freed value within 4σ of the truth (σ from the
        // reported covariance; 4σ is exceeded by a Gaussian error with
        // probability 6e-5, so by any of 25 with 0.16 %). The high-order
        // monomials are only large near the sensor's corners, so their σ
        // is large (about 1 to 30 mm for coefficients whose true values are
        // near 1e-6 mm): the check is that the fit and its covariance
        // agree, which the noise-free check below sharpens.
        for (k, name) in cov.names().iter().enumerate() {
            let sd = cov.matrix()[(k, k)].sqrt();
            let err = r.model.get(name).unwrap() - truth.get(name).unwrap();
            assert!(sd.is_finite() && sd > 0.0, "{label} {name}: σ {sd:e}");
            assert!(
                err.abs() <= 4.0 * sd,
                "{label} {name}: error {err:e}, σ {sd:e}"
            );
            // Noise-free, the same fit stops at the exact-fit floor (RMS
            // 1e-10 mm against σ̂ ≈ 0.18 mm at 1 µm on the template plane):
            // its errors, linear in the residuals, are a few 1e-9 σ; 1e-6 σ
            // leaves room for the stopping rule.
            let exact = noise_free_errors[k];
            assert!(
                exact.abs() <= 1e-6 * sd,
                "noise-free {name}: error {exact:e}, σ at 1 µm {sd:e}"
            );
        }
        // (d) continued: the rows follow the request. The same fit with the
        // stage's names in the model's own order gives the same matrix,
        // permuted accordingly (only rounding differs: 1e-6 of σ_i σ_j
        // allows for the conditioning of the nearly collinear monomials).
        let mut sorted = stage_names.clone();
        sorted.sort_by_key(|n| truth.index(n).unwrap());
        assert_ne!(sorted, stage_names);
        let reordered = RefineOptions {
            free_stage_parameters: sorted,
            ..options.clone()
        };
        let cov2 = covariance(data, &r, &reordered).unwrap();
        assert_eq!(cov2.names(), reordered.free_names());
        for (i, a) in cov.names().iter().enumerate() {
            for (j, b) in cov.names().iter().enumerate() {
                let (i2, j2) = (
                    cov2.names().iter().position(|n| n == a).unwrap(),
                    cov2.names().iter().position(|n| n == b).unwrap(),
                );
                let (x, y) = (cov.matrix()[(i, j)], cov2.matrix()[(i2, j2)]);
                assert!(
                    (x - y).abs() <= 1e-6 * (cov.matrix()[(i, i)] * cov.matrix()[(j, j)]).sqrt(),
                    "{a},{b}: {x:e} vs {y:e}"
                );
            }
        }
    }
}
