//! Refinement on synthetic data: exact recovery without noise, and the
//! reported covariance against the Monte Carlo spread with noise.

mod support;

use psdcal_calib::{covariance, refine, CostKind, RefineOptions};
use psdcal_model::{Param, SensorModel};
use support::{assert_recovered, perturbed, scenario};

#[test]
fn noise_free_recovery_both_lenses_both_costs() {
    for (name, truth) in [
        ("lens1", SensorModel::paper_lens1()),
        ("lens2", SensorModel::paper_lens2()),
    ] {
        let s = scenario(truth, 9, 0.0, 7);
        let (m0, p0) = perturbed(&truth, &s.poses);
        for cost in [CostKind::Template, CostKind::Image] {
            let options = RefineOptions {
                cost,
                ..RefineOptions::default()
            };
            let r = refine(&s.data, m0, &p0, &options).unwrap();
            assert!(r.report.termination.converged(), "{name}: {:?}", r.report);
            assert!(r.cost < 1e-12, "{name} {cost:?}: residual {:e} mm²", r.cost);
            assert_recovered(name, &r.sensor_model(), &truth, &options.free);
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
    let free = vec![
        Param::F,
        Param::Cx,
        Param::Cy,
        Param::Skew,
        Param::K1,
        Param::K2,
        Param::K3,
        Param::P1,
        Param::P2,
    ];
    let options = RefineOptions {
        free: free.clone(),
        ..RefineOptions::default()
    };
    let r = refine(&s.data, m0, &p0, &options).unwrap();
    assert!(r.cost < 1e-12, "residual {:e}", r.cost);
    assert_recovered("full", &r.sensor_model(), &truth, &free);
}

#[test]
fn noise_free_recovery_with_l1_freed_on_psd_distortion() {
    for truth in [SensorModel::paper_lens1(), SensorModel::paper_lens2()] {
        let mut truth = truth;
        truth.distortion.l1 = SensorModel::PAPER_L1;
        let s = scenario(truth, 9, 0.0, 5);
        let (mut m0, p0) = perturbed(&truth, &s.poses);
        m0.distortion.l1 = 0.8 * SensorModel::PAPER_L1;
        let free = vec![
            Param::F,
            Param::Cx,
            Param::Cy,
            Param::K1,
            Param::K2,
            Param::L1,
        ];
        let options = RefineOptions {
            free: free.clone(),
            ..RefineOptions::default()
        };
        let r = refine(&s.data, m0, &p0, &options).unwrap();
        assert!(r.cost < 1e-12, "residual {:e}", r.cost);
        assert_recovered("l1", &r.sensor_model(), &truth, &free);
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
        let r = refine(&data, m0, &p0, &options).unwrap();
        let cov = covariance(&data, &r, &options).unwrap();
        estimates.push([
            r.sensor_model().intrinsics.f,
            r.sensor_model().intrinsics.cx,
            r.sensor_model().intrinsics.cy,
        ]);
        reported.push([
            cov.std(Param::F).unwrap(),
            cov.std(Param::Cx).unwrap(),
            cov.std(Param::Cy).unwrap(),
        ]);
    }
    for (k, name) in ["f", "cx", "cy"].iter().enumerate() {
        let mean = estimates.iter().map(|e| e[k]).sum::<f64>() / trials as f64;
        let var =
            estimates.iter().map(|e| (e[k] - mean).powi(2)).sum::<f64>() / (trials - 1) as f64;
        let empirical = var.sqrt();
        let predicted = reported.iter().map(|r| r[k]).sum::<f64>() / trials as f64;
        println!(
            "{name}: empirical std {empirical:.4e}, reported σ {predicted:.4e}, ratio {:.3}",
            empirical / predicted
        );
        // With 60 trials the sample std itself scatters by about 1/sqrt(2·59) ≈ 9 %:
        // 25 % is nearly three of those.
        assert!(
            (empirical / predicted - 1.0).abs() < 0.25,
            "{name}: empirical std {empirical:e} vs reported {predicted:e}"
        );
    }
}

#[test]
fn robust_loss_resists_outliers_and_reports_them() {
    use psdcal_calib::{fit_statistics, RobustLoss};
    let truth = SensorModel::paper_lens2();
    let sigma_mm = 3e-4;
    let mut s = scenario(truth, 9, sigma_mm, 21);
    // Six gross outliers: 0.3 mm (1000 σ) displacements.
    let bad = [(0, 3), (1, 7), (2, 1), (4, 12), (6, 5), (8, 9)];
    for &(i, k) in &bad {
        s.data.images[i].points[k].measured.x += 0.3;
    }
    let (m0, p0) = perturbed(&truth, &s.poses);
    let plain = refine(&s.data, m0, &p0, &RefineOptions::default()).unwrap();
    // Huber scale: 3 σ on the template plane (σ_template ≈ σ · depth / f ≈ 0.04 mm).
    let robust = Some(RobustLoss::Huber { scale: 0.12 });
    let options = RefineOptions {
        robust,
        ..RefineOptions::default()
    };
    let r = refine(&s.data, m0, &p0, &options).unwrap();
    let clean = scenario(truth, 9, sigma_mm, 21);
    let reference = refine(&clean.data, m0, &p0, &RefineOptions::default()).unwrap();
    let cov = covariance(&clean.data, &reference, &RefineOptions::default()).unwrap();
    let sigma_f = cov.std(Param::F).unwrap();
    // Robust: within 3 σ of the outlier-free estimate; plain: pulled far away.
    let robust_shift =
        (r.sensor_model().intrinsics.f - reference.sensor_model().intrinsics.f).abs();
    let plain_shift =
        (plain.sensor_model().intrinsics.f - reference.sensor_model().intrinsics.f).abs();
    println!("σ_f {sigma_f:.3e}: robust shift {robust_shift:.3e}, plain shift {plain_shift:.3e}");
    assert!(
        robust_shift < 3.0 * sigma_f,
        "robust estimate moved {robust_shift:e} (σ {sigma_f:e})"
    );
    assert!(
        plain_shift > 10.0 * robust_shift,
        "plain least squares should suffer from the outliers"
    );
    let stats = fit_statistics(&s.data, &r.model, &r.poses, options.cost, robust);
    let mut flagged: Vec<(String, usize)> = stats
        .outliers
        .iter()
        .map(|p| (p.image.clone(), p.led))
        .collect();
    flagged.sort();
    let mut expected: Vec<(String, usize)> = bad
        .iter()
        .map(|&(i, k)| (format!("{}", i + 1), k))
        .collect();
    expected.sort();
    assert_eq!(
        flagged, expected,
        "exactly the displaced points are flagged"
    );
}

#[test]
fn fit_statistics_agree_with_the_cost() {
    use psdcal_calib::fit_statistics;
    let truth = SensorModel::paper_lens1();
    let s = scenario(truth, 9, 5e-4, 4);
    let (m0, p0) = perturbed(&truth, &s.poses);
    let r = refine(&s.data, m0, &p0, &RefineOptions::default()).unwrap();
    let stats = fit_statistics(&s.data, &r.model, &r.poses, CostKind::Template, None);
    assert!((stats.residual_mm2 - r.cost).abs() <= 1e-12 * r.cost);
    assert_eq!(stats.points, 126);
    assert_eq!(stats.per_image.len(), 9);
    let from_images: f64 = stats
        .per_image
        .iter()
        .map(|i| i.rms_template_mm.powi(2) * i.points as f64)
        .sum();
    assert!((from_images - stats.residual_mm2).abs() <= 1e-12 * r.cost);
    // Image-plane RMS near the injected noise: sqrt(2)·σ per point, less the
    // fraction absorbed by the 59 fitted parameters out of 252 coordinates.
    let expected = 5e-4 * (2.0f64 * (252.0 - 59.0) / 252.0).sqrt();
    assert!(
        (stats.rms_image_mm / expected - 1.0).abs() < 0.2,
        "{} vs {expected}",
        stats.rms_image_mm
    );
    assert!(stats
        .worst_points
        .windows(2)
        .all(|w| w[0].template_mm >= w[1].template_mm));
}
