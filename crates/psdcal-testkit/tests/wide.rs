//! The wide scenarios keep their contract (`psdcal_testkit::wide`): seeded
//! draws that are reproducible, inside the documented ranges, with measured
//! points that are the full model's projections plus the stated noise.

use nalgebra::Vector3;
use psdcal_testkit::wide::{snr_db_equivalent, Lens, ACTIVE_HALF_SIDE_MM, MIN_POINTS_PER_IMAGE};
use psdcal_testkit::WideScenario;

const DRAWS: u64 = 200;

fn scenarios() -> Vec<WideScenario> {
    (0..DRAWS).map(WideScenario::draw).collect()
}

#[test]
fn a_scenario_is_a_function_of_its_index() {
    assert_eq!(WideScenario::draw(17), WideScenario::draw(17));
    assert_ne!(WideScenario::draw(17), WideScenario::draw(18));
}

#[test]
fn draws_stay_in_their_documented_ranges() {
    for s in scenarios() {
        let (i, d) = (&s.truth.intrinsics, &s.truth.distortion);
        let (f0, k1_0) = match s.lens {
            Lens::One => (25.0, 2e-3),
            Lens::Two => (8.0, 1e-2),
        };
        assert!((i.f / f0 - 1.0).abs() <= 0.1, "{}: f {}", s.index, i.f);
        assert!(i.cx.abs() <= 0.8 && i.cy.abs() <= 0.8, "{}", s.index);
        assert!(
            (0.5..=1.5).contains(&(d.k1 / k1_0)),
            "{}: k1 {}",
            s.index,
            d.k1
        );
        assert!(d.l1 == 0.0 || (0.5e-3..=2.5e-3).contains(&d.l1.abs()));
        assert!((9..=20).contains(&s.images.len()));
        assert!((0.5..=2.0).contains(&s.template_scale));
        assert!(s.sigma_mm == 0.0 || (1e-5..=1e-2).contains(&s.sigma_mm));
        for image in &s.images {
            assert!(image.points.len() >= MIN_POINTS_PER_IMAGE);
            assert!(image.points.windows(2).all(|w| w[0].0 < w[1].0));
            // The tilt, read from the pose: the template normal against the
            // optical axis.
            let normal = image.view.pose.rotation() * Vector3::z();
            let tilt = normal.z.clamp(-1.0, 1.0).acos().to_degrees();
            assert!(
                (5.0 - 1e-9..=45.0 + 1e-9).contains(&tilt),
                "{}: tilt {tilt}",
                s.index
            );
            if s.sigma_mm == 0.0 {
                for (_, m) in &image.points {
                    assert!(m.x.abs() < ACTIVE_HALF_SIDE_MM && m.y.abs() < ACTIVE_HALF_SIDE_MM);
                }
            }
        }
    }
}

#[test]
fn the_draw_spans_lenses_psd_distortion_noise_and_partial_images() {
    let all = scenarios();
    let count = |pred: &dyn Fn(&WideScenario) -> bool| all.iter().filter(|s| pred(s)).count();
    let n = DRAWS as f64;
    // Binomial counts within 4 standard deviations of their expectation.
    let within =
        |count: usize, p: f64| (count as f64 - n * p).abs() <= 4.0 * (n * p * (1.0 - p)).sqrt();
    assert!(within(count(&|s| s.lens == Lens::One), 0.5));
    assert!(within(count(&|s| s.has_psd_distortion()), 0.5));
    assert!(within(count(&|s| s.truth.distortion.l1 > 0.0), 0.25));
    assert!(within(count(&|s| s.sigma_mm == 0.0), 0.2));
    // Some images lose LEDs off the active area; some scenarios lose many.
    assert!(
        count(&|s| s.images.iter().any(|i| i.points.len() < s.template.len())) > DRAWS as usize / 2
    );
    assert!(count(&|s| s.kept_fraction() < 0.8) > 0);
}

#[test]
fn measured_points_are_the_full_models_projections_plus_the_stated_noise() {
    let mut normalised = Vec::new();
    for s in scenarios() {
        for image in &s.images {
            for &(led, m) in &image.points {
                let exact = psdcal_model::Model::standard(&s.truth)
                    .project_to_tolerance(&image.view.pose, &s.template[led])
                    .expect("kept points project");
                if s.sigma_mm == 0.0 {
                    assert!((m - exact).norm() < 1e-12, "{}: {m} vs {exact}", s.index);
                } else {
                    normalised.push((m.x - exact.x) / s.sigma_mm);
                    normalised.push((m.y - exact.y) / s.sigma_mm);
                }
            }
        }
    }
    // Standard normal: the mean within 5 standard errors of 0, the variance
    // within 5 of its standard errors (√(2/n)) of 1.
    let n = normalised.len() as f64;
    let mean = normalised.iter().sum::<f64>() / n;
    let var = normalised.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / (n - 1.0);
    assert!(mean.abs() < 5.0 / n.sqrt(), "mean {mean} over {n}");
    assert!(
        (var - 1.0).abs() < 5.0 * (2.0 / n).sqrt(),
        "variance {var} over {n}"
    );
}

#[test]
fn the_snr_mapping_is_the_robustness_experiments() {
    assert!((snr_db_equivalent(4e-4) - 40.0).abs() < 1e-12);
    assert!((snr_db_equivalent(4e-4 * 10f64.powf(0.5)) - 30.0).abs() < 1e-12);
    assert!(snr_db_equivalent(0.0).is_infinite());
}
