//! Refinement on synthetic data: exact recovery without noise, and the
//! reported covariance against the Monte Carlo spread with noise.

mod support;

use psdcal_calib::{covariance, refine, CostKind, RefineOptions};
use psdcal_model::{Param, SensorModel};
use support::{perturbed, scenario};

fn assert_recovered(name: &str, got: &SensorModel, truth: &SensorModel, free: &[Param]) {
    for p in free {
        let (g, t) = (got.get(*p), truth.get(*p));
        // Relative 1e-6 where the value is not zero; absolute otherwise, in the
        // parameter's own scale.
        let scale = match p {
            Param::F | Param::Cx | Param::Cy => t.abs().max(1.0),
            _ => t.abs().max(1e-8),
        };
        assert!((g - t).abs() <= 1e-6 * scale, "{name}: {p} = {g:e}, truth {t:e}");
    }
}

#[test]
fn noise_free_recovery_both_lenses_both_costs() {
    for (name, truth) in [("lens1", SensorModel::paper_lens1()), ("lens2", SensorModel::paper_lens2())] {
        let s = scenario(truth, 9, 0.0, 7);
        let (m0, p0) = perturbed(&truth, &s.poses);
        for cost in [CostKind::Template, CostKind::Image] {
            let options = RefineOptions { cost, ..RefineOptions::default() };
            let r = refine(&s.data, &m0, &p0, &options).unwrap();
            assert!(r.report.termination.converged(), "{name}: {:?}", r.report);
            assert!(r.cost < 1e-12, "{name} {cost:?}: residual {:e} mm²", r.cost);
            assert_recovered(name, &r.model, &truth, &options.free);
        }
    }
}

#[test]
fn noise_free_recovery_with_every_lens_term_freed() {
    let mut truth = SensorModel::paper_lens2();
    truth.intrinsics.skew = 0.01;
    truth.distortion.k3 = 2e-7;
    truth.distortion.p1 = 3e-4;
    truth.distortion.p2 = -2e-4;
    let s = scenario(truth, 9, 0.0, 11);
    let (m0, p0) = perturbed(&truth, &s.poses);
    let free = vec![Param::F, Param::Cx, Param::Cy, Param::Skew, Param::K1, Param::K2, Param::K3, Param::P1, Param::P2];
    let options = RefineOptions { free: free.clone(), ..RefineOptions::default() };
    let r = refine(&s.data, &m0, &p0, &options).unwrap();
    assert!(r.cost < 1e-12, "residual {:e}", r.cost);
    assert_recovered("full", &r.model, &truth, &free);
}

#[test]
fn noise_free_recovery_with_l1_freed_on_psd_distortion() {
    for truth in [SensorModel::paper_lens1(), SensorModel::paper_lens2()] {
        let mut truth = truth;
        truth.distortion.l1 = SensorModel::PAPER_L1;
        let s = scenario(truth, 9, 0.0, 5);
        let (mut m0, p0) = perturbed(&truth, &s.poses);
        m0.distortion.l1 = 0.8 * SensorModel::PAPER_L1;
        let free = vec![Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2, Param::L1];
        let options = RefineOptions { free: free.clone(), ..RefineOptions::default() };
        let r = refine(&s.data, &m0, &p0, &options).unwrap();
        assert!(r.cost < 1e-12, "residual {:e}", r.cost);
        assert_recovered("l1", &r.model, &truth, &free);
    }
}

#[test]
fn monte_carlo_spread_matches_reported_sigma() {
    // Lens 2, Gaussian point noise of 2 µm per coordinate (a noisy sensor:
    // the paper's 40 dB chain corresponds to about 0.3 µm), 60 seeded trials
    // over the same poses.
    let truth = SensorModel::paper_lens2();
    let sigma_mm = 2e-3;
    let trials = 60;
    let base = scenario(truth, 9, 0.0, 3);
    let options = RefineOptions::default();
    let mut estimates: Vec<[f64; 3]> = Vec::new();
    let mut reported: Vec<[f64; 3]> = Vec::new();
    for trial in 0..trials {
        let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(1000 + trial);
        let data = support::observe(&truth, &base.poses, sigma_mm, &mut rng);
        let (m0, p0) = perturbed(&truth, &base.poses);
        let r = refine(&data, &m0, &p0, &options).unwrap();
        let cov = covariance(&data, options.cost, &options.free, None, &r.model, &r.poses, r.cost).unwrap();
        estimates.push([r.model.intrinsics.f, r.model.intrinsics.cx, r.model.intrinsics.cy]);
        reported.push([
            cov.std(Param::F).unwrap(),
            cov.std(Param::Cx).unwrap(),
            cov.std(Param::Cy).unwrap(),
        ]);
    }
    for (k, name) in ["f", "cx", "cy"].iter().enumerate() {
        let mean = estimates.iter().map(|e| e[k]).sum::<f64>() / trials as f64;
        let var = estimates.iter().map(|e| (e[k] - mean).powi(2)).sum::<f64>() / (trials - 1) as f64;
        let empirical = var.sqrt();
        let predicted = reported.iter().map(|r| r[k]).sum::<f64>() / trials as f64;
        println!("{name}: empirical std {empirical:.4e}, reported σ {predicted:.4e}, ratio {:.3}", empirical / predicted);
        // With 60 trials the sample std itself scatters by about 1/sqrt(2·59) ≈ 9 %:
        // 25 % is nearly three of those.
        assert!(
            (empirical / predicted - 1.0).abs() < 0.25,
            "{name}: empirical std {empirical:e} vs reported {predicted:e}"
        );
    }
}
