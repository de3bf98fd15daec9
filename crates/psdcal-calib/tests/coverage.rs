//! Issue 12, point 4: the reported σ covers the truth. Over seeded trials
//! in wide conditions (`tests/support/coverage.rs`: wide scenarios as drawn,
//! noisy, l1 known; and the hard condition, lens 1 and lens 2 at 0.05 mm
//! point noise on 10–11 images), |error| ≤ 3σ for at least 97 % of the
//! (parameter, trial) pairs of the trials the calibration does not flag
//! (`Trial::flagged`: the diagnostics `uncertainty_unreliable`, whose
//! curvature part is the ±3σ walk confirmed by the profile, or
//! `model_misfit`).
//!
//! Derived bounds: at exact Gaussian coverage a pair misses 3σ with
//! probability 0.27 %; the test asks 97 %, which the measured figure (99.2 %
//! on 1 085 pairs, EXPERIMENTS.md) clears with room for the sample here.
//! The check must not flag its way to a pass: at most 5 % of the wide
//! trials (measured 1 of 158: a wrong minimum, `model_misfit`) and of the
//! hard lens-2 trials (σ covers: measured 0 of 40) may be flagged; and it
//! must see the hard lens-1 condition, whose 3σ coverage is 0.905 (k1
//! 0.70): at least a quarter of its trials (measured 20 of 40; coverage of
//! the others 0.94). Release mode: `cargo test --release -p psdcal-calib
//! --test coverage`.
//!
//! Also: the bootstrap σ against the linear σ on a well-conditioned case,
//! and the bootstrap's independence of the thread count.

#[path = "support/mod.rs"]
mod support;

use psdcal_calib::covariance::{covariance_with, CovarianceMethod};
use psdcal_calib::profile::profile_at_three_sigma;
use psdcal_calib::{calibrate, BootstrapOptions, Uncertainty};
use psdcal_testkit::wide::Lens;
use psdcal_testkit::WideScenario;
use support::coverage::{covered, hard_geometry, renoised, Trial, FREE, HARD_SEED_BASE};

/// Trials of each kind (debug builds run fewer).
fn trials(release: u64) -> u64 {
    if cfg!(debug_assertions) {
        release / 5
    } else {
        release
    }
}

#[test]
fn reported_sigma_covers_the_truth_or_is_flagged() {
    let mut all = Vec::new();
    let wide: Vec<Trial> = (0..trials(200))
        .filter_map(|i| {
            let s = WideScenario::draw(i);
            (s.sigma_mm > 0.0)
                .then(|| Trial::run(i, &s, s.sigma_mm, &support::wide::data(&s), |_| {}))
        })
        .collect();
    let failed = wide.iter().filter(|t| t.result.is_err()).count();
    assert_eq!(failed, 0, "every wide trial calibrates");
    let flagged = wide.iter().filter(|t| t.flagged()).count();
    assert!(
        flagged * 20 <= wide.len(),
        "{flagged} of {} wide trials flagged: the check flags too much to mean anything",
        wide.len()
    );
    all.extend(wide);
    for lens in [Lens::One, Lens::Two] {
        let s = WideScenario::draw(hard_geometry(lens));
        let hard: Vec<Trial> = (0..trials(40))
            .map(|t| Trial::run(t, &s, 0.05, &renoised(&s, 0.05, HARD_SEED_BASE + t), |_| {}))
            .collect();
        let flagged = hard.iter().filter(|t| t.flagged()).count();
        match lens {
            // Far outside the quadratic regime (σ(f)/f ≈ 6 %, k1 biased):
            // the profile finds σ understated on about half the trials
            // (measured 20 of 40).
            Lens::One => assert!(
                flagged * 4 >= hard.len(),
                "lens 1 at 0.05 mm: {flagged} of {} trials flagged; the check must see it",
                hard.len()
            ),
            // σ covers (0.995): nothing to flag (measured 0 of 40).
            Lens::Two => assert!(
                flagged * 20 <= hard.len(),
                "lens 2 at 0.05 mm: {flagged} of {} trials flagged, its σ covers",
                hard.len()
            ),
        }
        all.extend(hard);
    }
    let z: Vec<f64> = all
        .iter()
        .filter(|t| t.result.is_ok() && !t.flagged())
        .flat_map(Trial::z)
        .collect();
    assert!(z.len() >= 5 * 50, "{} pairs judged", z.len());
    let coverage = covered(&z, 3.0);
    assert!(
        coverage >= 0.97,
        "|error| ≤ 3σ for {coverage:.3} of {} (parameter, trial) pairs",
        z.len()
    );
    assert_eq!(FREE.len(), 5);
}

#[test]
fn bootstrap_sigma_agrees_with_the_linear_sigma() {
    // A well-conditioned case: lens 2, ≥ 18 images of the wide draw's
    // kind, moderate noise. The bootstrap σ estimates the same spread as the
    // analytic σ, with three relative errors (sd): the resampling, ≈ 1/√(2N)
    // (8 % for N = 80); the data's own images as the sample the bootstrap
    // draws from, ≈ 1/√(2n) for n images (the variance is an average over
    // n independent images: 16 % for 20); the analytic σ's, from σ² (dof >
    // 400: < 4 %). A 3-sd band of the combined error (≈ 0.55; measured ratios
    // 0.88–1.36).
    let index = (0..)
        .find(|&i| {
            let s = WideScenario::draw(i);
            s.lens == Lens::Two && s.images.len() >= 18
        })
        .expect("a lens-2 scenario with many images");
    let s = WideScenario::draw(index);
    let data = renoised(&s, 1e-3, HARD_SEED_BASE);
    let mut options = support::coverage::options(&s.truth);
    let linear = calibrate(&data, &options).expect("calibrates");
    assert!(linear.linearity.verdict.is_reliable());
    let n = if cfg!(debug_assertions) { 20 } else { 80 };
    options.uncertainty = Uncertainty::Bootstrap(BootstrapOptions {
        resamples: n,
        seed: 7,
    });
    let boot = calibrate(&data, &options).expect("bootstraps");
    let images = data.images.len() as f64;
    let tolerance = 3.0 * (1.0 / (2.0 * n as f64) + 1.0 / (2.0 * images) + 0.04f64.powi(2)).sqrt();
    for p in FREE {
        let (a, b) = (
            linear.covariance.std(p.name()).unwrap(),
            boot.covariance.std(p.name()).unwrap(),
        );
        assert!(
            (b / a - 1.0).abs() <= tolerance,
            "{}: bootstrap σ {b:.3e} against linear {a:.3e} (ratio {:.3}, tolerance {tolerance:.2})",
            p.name(),
            b / a
        );
    }
    assert_eq!(boot.bootstrap.as_ref().map(|r| r.resamples), Some(n));
    // The same estimate, only the covariance differs.
    assert_eq!(boot.model, linear.model);
}

#[test]
fn bootstrap_is_independent_of_the_thread_count() {
    let s = WideScenario::draw(hard_geometry(Lens::Two));
    let data = renoised(&s, 1e-3, HARD_SEED_BASE + 1);
    let mut options = support::coverage::options(&s.truth);
    options.uncertainty = Uncertainty::Bootstrap(BootstrapOptions {
        resamples: 12,
        seed: 3,
    });
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| calibrate(&data, &options).expect("bootstraps"))
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.covariance, two.covariance);
    // A different seed draws different resamples.
    options.uncertainty = Uncertainty::Bootstrap(BootstrapOptions {
        resamples: 12,
        seed: 4,
    });
    let other = calibrate(&data, &options).expect("bootstraps");
    assert_ne!(other.covariance.parameters, one.covariance.parameters);
}

#[test]
fn sandwich_reduces_to_the_linear_covariance_when_every_point_is_equally_noisy() {
    // Image-plane cost: r = project − m, so ∂r/∂m = −I and C̃ = I for every
    // point; then Σ Ãᵀ C̃ Ã = S, σ_m² = cost/dof and the sandwich is
    // σ² S⁻¹ exactly, pose blocks included (docs/model.md §4.6).
    use psdcal_calib::covariance::{covariance_with, CovarianceMethod};
    use psdcal_calib::{refine, CostKind};
    let s = WideScenario::draw(hard_geometry(Lens::Two));
    let data = renoised(&s, 1e-3, HARD_SEED_BASE + 2);
    let mut options = support::coverage::options(&s.truth).refine;
    options.cost = CostKind::Image;
    let start = psdcal_model::Model::standard(&s.truth);
    let fit = refine(&data, start, &s.poses(), &options).expect("refines");
    let linear = covariance_with(&data, &fit, &options, CovarianceMethod::Linear).unwrap();
    let sandwich = covariance_with(&data, &fit, &options, CovarianceMethod::Sandwich).unwrap();
    assert!((sandwich.sigma2 / linear.sigma2 - 1.0).abs() < 1e-9);
    let (a, b) = (linear.matrix(), sandwich.matrix());
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            let scale = (a[(i, i)] * a[(j, j)]).sqrt();
            assert!((a[(i, j)] - b[(i, j)]).abs() <= 1e-7 * scale, "({i}, {j})");
        }
    }
    for (p, q) in linear.pose_blocks.iter().zip(&sandwich.pose_blocks) {
        for i in 0..6 {
            for j in 0..6 {
                let scale = (p[(i, i)] * p[(j, j)]).sqrt();
                assert!((p[(i, j)] - q[(i, j)]).abs() <= 1e-7 * scale);
            }
        }
    }
}

/// The profile at ±3σ (docs/model.md §4.6) of a nearly linear fit rises
/// by the quadratic model's 9 s² at 3σ_lin: lens 2, 11 images, 1e-4 mm of noise.
/// The departure from a quadratic cost at 3σ scales with the noise (lens 2
/// at 0.05 mm: |ρ − 1| ≤ 0.43), so here it is below 0.001; the tolerance
/// 0.02 leaves a factor 20.
#[test]
fn profile_of_a_nearly_linear_fit_rises_as_the_quadratic() {
    let s = WideScenario::draw(hard_geometry(Lens::Two));
    let data = renoised(&s, 1e-4, HARD_SEED_BASE + 2);
    let options = support::coverage::options(&s.truth);
    let r = calibrate(&data, &options).expect("calibrates");
    let refined = r.refined();
    // The quadratic model's own σ (σ² S⁻¹; the reported sandwich σ differs
    // from it by a few per cent, and r by its square).
    let linear = covariance_with(&data, &refined, &options.refine, CovarianceMethod::Linear)
        .expect("covariance");
    let names = options.refine.free_names();
    let std: Vec<f64> = names.iter().map(|n| linear.std(n).expect("σ")).collect();
    let profile = profile_at_three_sigma(&data, &refined, &options.refine, &std);
    assert_eq!(profile.len(), FREE.len());
    for p in &profile {
        for rise in [p.minus, p.plus] {
            assert!((rise - 1.0).abs() < 0.02, "{p:?}");
        }
        assert!(!p.understated());
    }
}
