//! The map fit against ground truth (docs/model.md §8.3): synthetic scans of
//! known fields with seeded noise (ChaCha8 per trial).

use nalgebra::Vector2;
use psdcal_model::stages::MapBasis;
use psdcal_psdmap::{fit_psd_map, FitOptions, ModelChoice, PsdMapError};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// An exactly cubic displacement field (map direction, mm): ≈ 40 µm at the
/// corners of a 9 mm sensor.
fn cubic(m: &Vector2<f64>) -> Vector2<f64> {
    let (u, v) = (m.x / 4.5, m.y / 4.5);
    Vector2::new(
        1e-2 * (u * u * u - 0.6 * u * v * v + 0.3 * u * v + 0.2 * v),
        1e-2 * (0.8 * v * v * v - 0.5 * u * u * v - 0.4 * u * u + 0.1),
    )
}

/// A smooth field that no low polynomial holds exactly: growing towards the
/// edges, anisotropic (≈ 60 µm at the corners).
fn smooth(m: &Vector2<f64>) -> Vector2<f64> {
    let (u, v) = (m.x / 4.5, m.y / 4.5);
    Vector2::new(
        2e-2 * u * (1.0 + 0.8 * v * v).sqrt() * (0.5 * u * u).exp() - 5e-3 * (2.0 * v).sin(),
        1.5e-2 * v * (1.0 + u * u) + 4e-3 * (1.5 * u + v).cos(),
    )
}

/// A raster scan of `n × n` positions over ±`half` mm: measured points
/// (with noise `sigma_m`) and stage positions `m + field(m)` (with noise
/// `sigma_s`).
fn scan(
    field: fn(&Vector2<f64>) -> Vector2<f64>,
    n: usize,
    half: f64,
    sigma_m: f64,
    sigma_s: f64,
    seed: u64,
) -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let nm = Normal::new(0.0, sigma_m).unwrap();
    let ns = Normal::new(0.0, sigma_s).unwrap();
    let mut stage = Vec::new();
    let mut measured = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let t = Vector2::new(
                -half + 2.0 * half * i as f64 / (n - 1) as f64,
                -half + 2.0 * half * j as f64 / (n - 1) as f64,
            );
            let s = t + field(&t);
            stage.push(s + Vector2::new(ns.sample(&mut rng), ns.sample(&mut rng)));
            measured.push(t + Vector2::new(nm.sample(&mut rng), nm.sample(&mut rng)));
        }
    }
    (stage, measured)
}

/// RMS of the fitted map's error against the true field on a 41 × 41 grid
/// over ±`half` mm, mm.
fn error_vs_truth(
    fit: &psdcal_psdmap::PsdMapFit,
    field: fn(&Vector2<f64>) -> Vector2<f64>,
    half: f64,
) -> f64 {
    let mut s = 0.0;
    for i in 0..41 {
        for j in 0..41 {
            let m = Vector2::new(
                -half + 2.0 * half * i as f64 / 40.0,
                -half + 2.0 * half * j as f64 / 40.0,
            );
            s += (fit.map.displacement(&fit.block, &m) - field(&m)).norm_squared();
        }
    }
    (s / 1681.0).sqrt()
}

#[test]
fn cross_validation_picks_order_three_for_a_cubic_field() {
    let mut third = 0;
    for seed in 0..10 {
        let (stage, measured) = scan(cubic, 25, 4.5, 3e-4, 3e-4, seed);
        let options = FitOptions {
            seed,
            ..FitOptions::default()
        };
        let fit = fit_psd_map(&stage, &measured, &options).unwrap();
        if fit.map.basis() == (MapBasis::Polynomial { order: 3 }) {
            third += 1;
        }
        // Never an underfit: a model that cannot hold the cubic leaves ≥ µm
        // residuals, far above the noise's √2 · 0.42 µm.
        assert!(fit.cv_rms_mm < 1.2e-3, "seed {seed}: {:?}", fit.candidates);
    }
    assert!(third >= 9, "order 3 chosen in {third} of 10 seeds");
}

#[test]
fn a_known_field_is_recovered_to_its_predicted_error() {
    // Noise per axis: √(0.3² + 0.3²) µm ≈ 0.42 µm.
    let sigma = (2.0f64 * 3e-4 * 3e-4).sqrt();
    let (stage, measured) = scan(cubic, 37, 4.5, 3e-4, 3e-4, 7);
    let options = FitOptions {
        model: ModelChoice::Fixed(MapBasis::Polynomial { order: 3 }),
        ..FitOptions::default()
    };
    let fit = fit_psd_map(&stage, &measured, &options).unwrap();
    // σ per axis from 1369 points: relative sd ≈ 2 %.
    for s in [fit.sigma_mm.x, fit.sigma_mm.y] {
        assert!((s / sigma - 1.0).abs() < 0.08, "{s} vs {sigma}");
    }
    // The map's error against the truth agrees with its propagated σ (a
    // χ²-like sum of 20 coefficients' errors: within a factor 2).
    let err = error_vs_truth(&fit, cubic, 4.5);
    let ratio = err / fit.map_sigma_mm;
    assert!((0.5..2.0).contains(&ratio), "{err} vs {}", fit.map_sigma_mm);
    // And it is far below the scan's own noise (20 coefficients from 1369
    // points): about √(20/1369) of it.
    assert!(err < 0.3 * sigma, "{err}");
    assert!(fit.rejected.is_empty());

    // A field that is no polynomial: auto reaches a few tenths of a µm too.
    let (stage, measured) = scan(smooth, 37, 4.5, 3e-4, 3e-4, 8);
    let fit = fit_psd_map(&stage, &measured, &FitOptions::default()).unwrap();
    let err = error_vs_truth(&fit, smooth, 4.5);
    assert!(err < 0.5 * sigma, "{err} with {}", fit.map.basis().label());
    assert!(fit.cv_rms_mm < 1.1 * 2f64.sqrt() * sigma * 1.05);
}

#[test]
fn a_few_bad_points_are_rejected() {
    let (mut stage, measured) = scan(smooth, 37, 4.5, 3e-4, 3e-4, 9);
    let (clean_stage, _) = (stage.clone(), ());
    let bad = [3usize, 400, 401, 777, 1300];
    for (k, &i) in bad.iter().enumerate() {
        stage[i] += Vector2::new(5e-2, -3e-2 * k as f64);
    }
    let fit = fit_psd_map(&stage, &measured, &FitOptions::default()).unwrap();
    assert_eq!(fit.rejected, bad);
    let clean = fit_psd_map(&clean_stage, &measured, &FitOptions::default()).unwrap();
    let (e, e0) = (
        error_vs_truth(&fit, smooth, 4.5),
        error_vs_truth(&clean, smooth, 4.5),
    );
    assert!(e < 1.5 * e0 + 2e-5, "{e} vs {e0}");
}

#[test]
fn unusable_scans_are_typed_errors() {
    let (stage, measured) = scan(cubic, 5, 4.5, 3e-4, 3e-4, 1);
    let options = FitOptions {
        model: ModelChoice::Fixed(MapBasis::Polynomial { order: 6 }),
        ..FitOptions::default()
    };
    let e = fit_psd_map(&stage, &measured, &options).unwrap_err();
    assert!(
        matches!(
            e,
            PsdMapError::TooFewPoints {
                coefficients: 28,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("poly:6"), "{e}");
    let line: Vec<_> = (0..30).map(|i| Vector2::new(0.1 * i as f64, 0.0)).collect();
    assert!(matches!(
        fit_psd_map(&line, &line, &FitOptions::default()),
        Err(PsdMapError::Unusable { .. })
    ));
    let mut nan = measured.clone();
    nan[2].x = f64::NAN;
    assert!(fit_psd_map(&stage, &nan, &FitOptions::default()).is_err());
    // Too few for anything in auto.
    let e = fit_psd_map(&stage[..6], &measured[..6], &FitOptions::default()).unwrap_err();
    assert!(matches!(e, PsdMapError::NoCandidate { .. }), "{e}");
}
