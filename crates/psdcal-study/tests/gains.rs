//! Self-calibration of the amplifier gains (issue 7): the relative gains are
//! estimated with the optics from the same template images' electrode
//! amplitudes.

use psdcal_calib::{calibrate, CalibrateOptions, NoiseModel, RefineOptions};
use psdcal_model::{ChannelGains, Param};
use psdcal_sim::{simulate, Lens, SimulationOptions};
use psdcal_study::SimulationData;
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
            let (m, t) = (&r.sensor_model(), &sim.truth);
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
            let with_gains_aoa = sim.aoa_rms_error(&fitted.sensor_model(), &g);
            let ref_fit = calibrate(&reference.calibration_data(), &plain()).unwrap();
            let reference_aoa =
                reference.aoa_rms_error(&ref_fit.sensor_model(), &ChannelGains::UNIT);
            let plain_deg = (seed < plain_seeds).then(|| {
                let plain = calibrate(&sim.calibration_data(), &plain()).unwrap();
                sim.aoa_rms_error(&plain.sensor_model(), &ChannelGains::UNIT)
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

/// One scenario (poses, gains) measured again and again with fresh noise
/// through the signal chain and calibrated with the gains freed under
/// `noise`: per estimated quantity (f, cx, cy, then the three gains), the
/// Monte Carlo spread and the mean reported σ.
fn monte_carlo_spread(noise: NoiseModel, trials: u64) -> Vec<(String, f64, f64)> {
    use psdcal_calib::Observation;
    use psdcal_model::psd::{electrode_currents, impact_point};
    let options = SimulationOptions {
        lens: Lens::Two,
        snr_db: Some(40.0),
        imbalance: true,
        ..SimulationOptions::default()
    };
    let sim = simulate(&options, &mut ChaCha8Rng::seed_from_u64(77)).unwrap();
    let calibrate_options = CalibrateOptions {
        refine: RefineOptions {
            noise,
            ..with_gains().refine
        },
        ..with_gains()
    };
    let runs: Vec<(Vec<f64>, Vec<f64>, Vec<String>)> = (0..trials)
        .into_par_iter()
        .map(|t| {
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
            }
            data.amplitudes = Some(amplitudes);
            let r = calibrate(&data, &calibrate_options).unwrap();
            let m = &r.sensor_model().intrinsics;
            let mut values = vec![m.f, m.cx, m.cy];
            values.extend(r.gains.unwrap().to_array());
            let cov = &r.covariance;
            let mut sigmas: Vec<f64> = [Param::F, Param::Cx, Param::Cy]
                .iter()
                .map(|p| cov.std(*p).unwrap())
                .collect();
            sigmas.extend(cov.gain_std().unwrap());
            let names = ["f", "cx", "cy", "g_x2", "g_y1", "g_y2"]
                .map(String::from)
                .to_vec();
            (values, sigmas, names)
        })
        .collect();
    let n = trials as f64;
    (0..6)
        .map(|k| {
            let mean = runs.iter().map(|r| r.0[k]).sum::<f64>() / n;
            let spread =
                (runs.iter().map(|r| (r.0[k] - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            let sigma = runs.iter().map(|r| r.1[k]).sum::<f64>() / n;
            (runs[0].2[k].clone(), spread, sigma)
        })
        .collect()
}

#[test]
fn reported_gain_sigma_matches_the_monte_carlo_spread() {
    // 60 trials: a sample standard deviation scatters by about 1/√(2·59) ≈
    // 9 %; 25 % is nearly three of those. The unweighted fit's σ² (JᵀJ)⁻¹
    // assumes equal noise on every point, which the per-channel SNR breaks
    // (points near the electrodes are quieter), so only the gains, which
    // the issue asks about, are held to it.
    for (name, spread, sigma) in monte_carlo_spread(NoiseModel::Uniform, 60).iter().skip(3) {
        println!(
            "uniform {name}: spread {spread:.3e}, reported σ {sigma:.3e}, ratio {:.3}",
            spread / sigma
        );
        assert!(
            (spread / sigma - 1.0).abs() < 0.25,
            "{name}: spread {spread:e} vs σ {sigma:e}"
        );
    }
}

#[test]
fn weighted_fit_sigma_matches_the_monte_carlo_spread() {
    // Under the noise model that generated the data the weighted fit's
    // covariance is the generalised-least-squares one, right for every
    // parameter. 300 trials: a sample standard deviation scatters by
    // 1/√(2·299) ≈ 4.1 %; 15 % is about 3.5 of those (measured: within 4 %).
    for (name, spread, sigma) in monte_carlo_spread(NoiseModel::ChannelSnr, 300) {
        println!(
            "channel-snr {name}: spread {spread:.3e}, reported σ {sigma:.3e}, ratio {:.3}",
            spread / sigma
        );
        assert!(
            (spread / sigma - 1.0).abs() < 0.15,
            "{name}: spread {spread:e} vs σ {sigma:e}"
        );
    }
}
