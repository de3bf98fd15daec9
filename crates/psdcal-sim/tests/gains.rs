//! Self-calibration of the amplifier gains (issue 7): the relative gains are
//! estimated with the optics from the same template images' electrode
//! amplitudes.

use psdcal_calib::{calibrate, CalibrateOptions, RefineOptions};
use psdcal_model::ChannelGains;
use psdcal_sim::{simulate, Lens, SimulationOptions};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

fn with_gains() -> CalibrateOptions {
    CalibrateOptions {
        refine: RefineOptions {
            fit_gains: true,
            ..RefineOptions::default()
        },
        ..CalibrateOptions::default()
    }
}

fn plain() -> CalibrateOptions {
    CalibrateOptions::default()
}

#[test]
fn noise_free_imbalance_is_recovered_exactly() {
    for lens in [Lens::Two, Lens::One] {
        for seed in [1, 2] {
            let options = SimulationOptions {
                lens,
                snr_db: None,
                imbalance: true,
                ..SimulationOptions::default()
            };
            let sim = simulate(&options, &mut ChaCha8Rng::seed_from_u64(seed)).unwrap();
            let r = calibrate(&sim.calibration_data(), &with_gains()).unwrap();
            let g = r.gains.unwrap();
            for (est, truth) in g.to_array().iter().zip(sim.gains.to_array()) {
                assert!(
                    (est / truth - 1.0).abs() < 1e-9,
                    "{lens:?} seed {seed}: gain {est} vs {truth}"
                );
            }
            let (m, t) = (&r.model, &sim.truth);
            for (name, e, tv) in [
                ("f", m.intrinsics.f, t.intrinsics.f),
                ("cx", m.intrinsics.cx, t.intrinsics.cx),
                ("cy", m.intrinsics.cy, t.intrinsics.cy),
                ("k1", m.distortion.k1, t.distortion.k1),
            ] {
                assert!(
                    (e - tv).abs()
                        <= 1e-6
                            * tv.abs()
                                .max(1.0)
                                .min(if name == "k1" { tv.abs() } else { f64::MAX }),
                    "{lens:?}: {name} {e} vs {tv}"
                );
            }
            assert!(
                (m.distortion.k2 - t.distortion.k2).abs() < 1e-6 * t.distortion.k2.abs().max(1e-8)
            );
            assert!(
                r.statistics.residual_mm2 < 1e-12,
                "residual {:e}",
                r.statistics.residual_mm2
            );
            assert!(sim.aoa_rms_error(m, &g) < 1e-9);
        }
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[test]
fn self_calibration_removes_the_imbalance_at_40_db() {
    // Lens 2, 40 dB, nine images, the paper's imbalance. A seed's balanced
    // and unbalanced data share the poses and the noise draws (the simulator
    // draws the gains even when it does not apply them), so each per-seed
    // ratio isolates what the imbalance and the three extra parameters cost.
    // The ratio still scatters from seed to seed (the gains' own estimation
    // error is not paired): medians over disjoint blocks of 30 seeds spread
    // with a standard deviation of about 0.07 around 1.10, so 30 seeds could
    // not tell 1.1 from 1.2. 200 seeds bring the median's standard error to
    // about 0.03, a third of the distance to the 1.2 the issue asks for.
    let seeds = 200;
    let plain_seeds = 30;
    // Seeds run in parallel; each owns its generator, so the result does not
    // depend on the thread count.
    let per_seed: Vec<(f64, Option<f64>, [f64; 3])> = (0..seeds)
        .into_par_iter()
        .map(|seed| {
            let imbalanced = SimulationOptions {
                lens: Lens::Two,
                snr_db: Some(40.0),
                imbalance: true,
                ..SimulationOptions::default()
            };
            let sim = simulate(&imbalanced, &mut ChaCha8Rng::seed_from_u64(100 + seed)).unwrap();
            let balanced = SimulationOptions {
                imbalance: false,
                ..imbalanced.clone()
            };
            let reference =
                simulate(&balanced, &mut ChaCha8Rng::seed_from_u64(100 + seed)).unwrap();
            assert_eq!(sim.poses, reference.poses);
            let fitted = calibrate(&sim.calibration_data(), &with_gains()).unwrap();
            let g = fitted.gains.unwrap();
            let with_gains_aoa = sim.aoa_rms_error(&fitted.model, &g);
            let ref_fit = calibrate(&reference.calibration_data(), &plain()).unwrap();
            let reference_aoa = reference.aoa_rms_error(&ref_fit.model, &ChannelGains::UNIT);
            let plain_deg = (seed < plain_seeds).then(|| {
                let plain = calibrate(&sim.calibration_data(), &plain()).unwrap();
                sim.aoa_rms_error(&plain.model, &ChannelGains::UNIT)
                    .to_degrees()
            });
            let truth = sim.gains.to_array();
            let errors = std::array::from_fn(|k| g.to_array()[k] / truth[k] - 1.0);
            (with_gains_aoa / reference_aoa, plain_deg, errors)
        })
        .collect();
    let ratios: Vec<f64> = per_seed.iter().map(|s| s.0).collect();
    let plain_deg: Vec<f64> = per_seed.iter().filter_map(|s| s.1).collect();
    let gain_errors: Vec<f64> = per_seed.iter().flat_map(|s| s.2).collect();
    let ratio = median(ratios);
    let gain_rms =
        (gain_errors.iter().map(|e| e * e).sum::<f64>() / gain_errors.len() as f64).sqrt();
    let plain = median(plain_deg);
    println!(
        "median AoA ratio {ratio:.3}, gain RMS error {:.4} %, AoA without gains {plain:.2}°",
        100.0 * gain_rms
    );
    assert!(ratio <= 1.2, "median ratio of AoA errors {ratio:.3}");
    // A ratio below 1 would mean the extra parameters carry no cost: a
    // pairing or simulation defect, not a better estimator.
    assert!(ratio >= 1.0, "median ratio of AoA errors {ratio:.3}");
    assert!(gain_rms <= 0.003, "gain RMS error {gain_rms:.5}");
    assert!(
        plain > 1.0,
        "without the gains freed the AoA error is degrees: {plain:.3}°"
    );
}

#[test]
fn reported_gain_sigma_matches_the_monte_carlo_spread() {
    use psdcal_calib::{ImageObservations, Observation};
    use psdcal_model::sensor::{electrode_currents, impact_point};
    // One scenario (poses, gains) measured again and again with fresh noise.
    let options = SimulationOptions {
        lens: Lens::Two,
        snr_db: Some(40.0),
        imbalance: true,
        ..SimulationOptions::default()
    };
    let sim = simulate(&options, &mut ChaCha8Rng::seed_from_u64(77)).unwrap();
    let trials = 60;
    let (mut estimates, mut sigmas): (Vec<[f64; 3]>, Vec<[f64; 3]>) = (Vec::new(), Vec::new());
    for t in 0..trials {
        let mut rng = ChaCha8Rng::seed_from_u64(5000 + t);
        let mut data = sim.calibration_data();
        let mut amplitudes = Vec::new();
        for (im, image) in data.images.iter_mut().zip(&sim.images) {
            let mut row = Vec::new();
            im.points = image
                .points
                .iter()
                .map(|p| {
                    let clean = electrode_currents(
                        &options.geometry,
                        &p.true_measured,
                        options.photocurrent_a * sim.gain_x1,
                    )
                    .apply_gains(&sim.gains);
                    let a = options
                        .chain
                        .measure(&clean, options.snr_db, &mut rng)
                        .unwrap();
                    row.push(a);
                    Observation {
                        led: p.led,
                        measured: impact_point(&options.geometry, &a).unwrap(),
                    }
                })
                .collect();
            amplitudes.push(row);
            let _: &ImageObservations = im;
        }
        data.amplitudes = Some(amplitudes);
        let r = calibrate(&data, &with_gains()).unwrap();
        estimates.push(r.gains.unwrap().to_array());
        sigmas.push(r.covariance.gain_std().unwrap());
    }
    for k in 0..3 {
        let n = trials as f64;
        let mean = estimates.iter().map(|e| e[k]).sum::<f64>() / n;
        let spread =
            (estimates.iter().map(|e| (e[k] - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let sigma = sigmas.iter().map(|s| s[k]).sum::<f64>() / n;
        println!(
            "gain {k}: spread {spread:.3e}, reported σ {sigma:.3e}, ratio {:.3}",
            spread / sigma
        );
        // 60 trials: a sample std scatters by about 9 %; 25 % is nearly three of those.
        assert!(
            (spread / sigma - 1.0).abs() < 0.25,
            "gain {k}: spread {spread:e} vs σ {sigma:e}"
        );
    }
}
