//! The signal chain of docs/model.md §6: Butterworth band-pass design, synthesis at
//! a given SNR, I/Q and RMS demodulation, the theoretical noise of the
//! estimate, determinism, and the impact point through the chain.
//!
//! Statistical tolerances come from the sample size: a mean is checked to
//! `4 σ/√n`, a standard deviation to `4/√(2(n−1))` relative (its sampling
//! error for a Gaussian), a variance over `n` samples to `5·√(2/n)`.

use std::f64::consts::{FRAC_1_SQRT_2, PI, TAU};

use nalgebra::Vector2;
use psdcal_model::psd::{electrode_currents, impact_point};
use psdcal_model::{Amplitudes, ChannelGains, PsdGeometry};
use psdcal_sim::butterworth::{BandPass, BandPlacement, FilterState, MAX_ORDER};
use psdcal_sim::signal::{noise_sigma, ChainConfig, Demodulation, SignalChain, SignalError};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const F0: f64 = 1000.0;
const B: f64 = 600.0;

fn warp(f: f64, fs: f64) -> f64 {
    (PI * f / fs).tan()
}

/// The analog Butterworth band-pass magnitude at the pre-warped frequency of
/// `f`, for the filter's own edges: `1/√(1 + ((Ω² − Ω0²)/(W Ω))^{2N})`.
fn butterworth_magnitude(filter: &BandPass, f: f64) -> f64 {
    let fs = filter.sample_rate_hz();
    let (lo, hi) = filter.band_edges_hz();
    let (w_lo, w_hi, w) = (warp(lo, fs), warp(hi, fs), warp(f, fs));
    let x = (w * w - w_lo * w_hi) / ((w_hi - w_lo) * w);
    1.0 / (1.0 + x.powi(2 * filter.order() as i32)).sqrt()
}

fn chain(config: ChainConfig) -> SignalChain {
    SignalChain::new(config).unwrap()
}

// ---------------------------------------------------------------- filter

#[test]
fn centred_filter_is_minus_3_db_at_its_edges_and_unity_at_f0() {
    for fs in [20_000.0, 50_000.0] {
        for order in 1..=4 {
            let filter = BandPass::centred(order, F0, B, fs).unwrap();
            assert_eq!(filter.order(), order);
            assert_eq!(filter.sections().len(), order);
            let (lo, hi) = filter.band_edges_hz();
            // Bandwidth B exactly, f0 the pre-warped geometric centre.
            assert!(
                (hi - lo - B).abs() < 1e-9,
                "fs {fs} N {order}: width {}",
                hi - lo
            );
            let centre = warp(lo, fs) * warp(hi, fs);
            assert!((centre / warp(F0, fs).powi(2) - 1.0).abs() < 1e-12);
            assert!((filter.centre_hz() - F0).abs() < 1e-9);
            // The edges lie above f0 ∓ B/2 (geometric placement), near the
            // analog values −B/2 + √(B²/4 + f0²) ± B/2.
            assert!(lo > F0 - B / 2.0 && hi > F0 + B / 2.0);
            assert!((lo - 744.03).abs() < 2.0, "lo = {lo}");
            for edge in [lo, hi] {
                let m = filter.magnitude(edge);
                assert!(
                    (m - FRAC_1_SQRT_2).abs() < 1e-9,
                    "fs {fs} N {order}: |H({edge})| = {m}"
                );
            }
            assert!((filter.magnitude(F0) - 1.0).abs() < 1e-9);
            assert!(
                filter.phase(F0).abs() < 1e-9,
                "phase at f0 {}",
                filter.phase(F0)
            );
            // Unity is the maximum.
            for f in [0.9 * F0, 0.99 * F0, 1.01 * F0, 1.1 * F0] {
                assert!(filter.magnitude(f) < 1.0);
            }
        }
    }
}

#[test]
fn filter_from_edges_is_minus_3_db_exactly_at_the_given_edges() {
    for fs in [20_000.0, 50_000.0] {
        for order in 1..=4 {
            let filter = BandPass::from_edges(order, 700.0, 1300.0, fs).unwrap();
            for edge in [700.0, 1300.0] {
                assert!((filter.magnitude(edge) - FRAC_1_SQRT_2).abs() < 1e-9);
            }
            let centre = fs / PI * (warp(700.0, fs) * warp(1300.0, fs)).sqrt().atan();
            assert!((filter.centre_hz() - centre).abs() < 1e-9);
            assert!((filter.magnitude(centre) - 1.0).abs() < 1e-9);
            // The arithmetic centre is off the peak: gain below 1 there, by
            // the Butterworth formula.
            let at_f0 = filter.magnitude(F0);
            assert!(at_f0 < 1.0 - 1e-8, "N {order}: |H(f0)| = {at_f0}");
            assert!((at_f0 - butterworth_magnitude(&filter, F0)).abs() < 1e-9);
            // `design` with the arithmetic placement is the same filter.
            let same = BandPass::design(order, F0, B, fs, BandPlacement::Arithmetic).unwrap();
            assert_eq!(same.band_edges_hz(), (700.0, 1300.0));
            assert!((same.magnitude(F0) - at_f0).abs() < 1e-12);
        }
    }
}

#[test]
fn filter_follows_the_butterworth_response_and_its_geometric_symmetry() {
    for fs in [20_000.0, 50_000.0] {
        for order in 1..=4 {
            let filter = BandPass::centred(order, F0, B, fs).unwrap();
            let w0_sq = warp(F0, fs).powi(2);
            for f in [
                50.0,
                300.0,
                650.0,
                800.0,
                950.0,
                1100.0,
                1500.0,
                3000.0,
                0.45 * fs,
            ] {
                let m = filter.magnitude(f);
                let expected = butterworth_magnitude(&filter, f);
                assert!(
                    (m - expected).abs() < 1e-9,
                    "fs {fs} N {order} f {f}: {m} vs {expected}"
                );
                // Symmetric in the pre-warped sense: Ω ↔ Ω0²/Ω.
                let mirror = fs / PI * (w0_sq / warp(f, fs)).atan();
                let mm = filter.magnitude(mirror);
                assert!(
                    (m - mm).abs() < 1e-9,
                    "fs {fs} N {order}: |H({f})| {m} vs |H({mirror})| {mm}"
                );
            }
            // Zeros at DC and Nyquist.
            assert!(filter.magnitude(0.0) < 1e-12);
            assert!(filter.magnitude(0.5 * fs) < 1e-12);
        }
    }
}

#[test]
fn filter_poles_are_inside_the_unit_circle_and_the_transient_decays() {
    for fs in [20_000.0, 50_000.0] {
        for order in 1..=MAX_ORDER {
            let filter = BandPass::centred(order, F0, B, fs).unwrap();
            let poles = filter.poles();
            assert_eq!(poles.len(), 2 * order);
            for p in &poles {
                assert!(
                    p.norm() < 1.0,
                    "fs {fs} N {order}: pole {p} on or outside the unit circle"
                );
            }
            // Narrow-band estimate of the slowest decay, π B sin(π/(2N)),
            // checked on a narrow band (60 Hz around 1 kHz).
            let narrow = BandPass::centred(order, F0, 60.0, fs).unwrap();
            let approx = PI * 60.0 * (PI / (2 * order) as f64).sin();
            let rate = narrow.decay_rate();
            assert!(
                (rate / approx - 1.0).abs() < 0.05,
                "N {order}: {rate} vs {approx}"
            );
        }
        // The impulse response of the default order falls below 1e-9 of its
        // peak within the settling time to 1e-11 (margin for the algebraic
        // prefactor of the repeated-pole transient).
        let filter = BandPass::centred(2, F0, B, fs).unwrap();
        let mut h = vec![0.0; (0.1 * fs) as usize];
        h[0] = 1.0;
        filter.filter(&mut h);
        let peak = h.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let settled = (filter.settling_time(1e-11) * fs).ceil() as usize;
        let tail = h[settled..].iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(tail < 1e-9 * peak, "tail {tail} peak {peak}");
        // … and not long before: at a tenth of that time it is still large.
        assert!(h[settled / 10..].iter().any(|v| v.abs() > 1e-3 * peak));
    }
}

#[test]
fn noise_bandwidth_matches_the_analog_butterworth() {
    // At a high sample rate the warping is negligible: ENBW of the analog
    // band-pass is B (π/2N) / sin(π/2N).
    for order in 1..=4 {
        let filter = BandPass::centred(order, F0, B, 400_000.0).unwrap();
        let x = PI / (2 * order) as f64;
        let expected = B * x / x.sin();
        let enbw = filter.equivalent_noise_bandwidth_hz();
        assert!(
            (enbw / expected - 1.0).abs() < 0.01,
            "N {order}: {enbw} vs {expected}"
        );
    }
}

#[test]
fn whole_slice_and_streaming_filters_agree_and_are_linear() {
    let filter = BandPass::centred(3, F0, B, 20_000.0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let x: Vec<f64> = (0..500).map(|_| rng.random::<f64>() - 0.5).collect();
    let u: Vec<f64> = (0..500).map(|_| rng.random::<f64>() - 0.5).collect();
    let mut y = x.clone();
    filter.filter(&mut y);
    let mut state = FilterState::new();
    for (xi, yi) in x.iter().zip(&y) {
        assert_eq!(state.process(&filter, *xi).to_bits(), yi.to_bits());
    }
    let mut yu = u.clone();
    filter.filter(&mut yu);
    let mut sum: Vec<f64> = x.iter().zip(&u).map(|(a, b)| 2.0 * a - 3.0 * b).collect();
    filter.filter(&mut sum);
    for i in 0..500 {
        assert!((sum[i] - (2.0 * y[i] - 3.0 * yu[i])).abs() < 1e-12);
    }
    // A steady sinusoid at f0 passes with unit gain and zero phase.
    let fs = 20_000.0;
    let mut s: Vec<f64> = (0..4000)
        .map(|n| (TAU * F0 * n as f64 / fs + 0.7).sin())
        .collect();
    filter.filter(&mut s);
    for (n, v) in s.iter().enumerate().skip(3000) {
        assert!((v - (TAU * F0 * n as f64 / fs + 0.7).sin()).abs() < 1e-9);
    }
}

#[test]
fn invalid_filter_parameters_are_typed_errors() {
    assert!(matches!(
        BandPass::centred(0, F0, B, 2e4),
        Err(SignalError::InvalidOrder { order: 0, .. })
    ));
    assert!(matches!(
        BandPass::centred(MAX_ORDER + 1, F0, B, 2e4),
        Err(SignalError::InvalidOrder { .. })
    ));
    assert!(matches!(
        BandPass::centred(2, 0.0, B, 2e4),
        Err(SignalError::InvalidParameter { name: "f0_hz", .. })
    ));
    assert!(matches!(
        BandPass::centred(2, F0, f64::NAN, 2e4),
        Err(SignalError::InvalidParameter { .. })
    ));
    assert!(matches!(
        BandPass::centred(2, F0, 2000.0, 2e4),
        Err(SignalError::BandwidthTooWide { .. })
    ));
    assert!(matches!(
        BandPass::centred(2, F0, B, 2500.0),
        Err(SignalError::BandAboveNyquist { .. })
    ));
    assert!(matches!(
        BandPass::centred(2, F0, B, f64::INFINITY),
        Err(SignalError::InvalidParameter { .. })
    ));
    assert!(matches!(
        BandPass::from_edges(2, 1300.0, 700.0, 2e4),
        Err(SignalError::InvalidParameter { .. })
    ));
    assert!(matches!(
        BandPass::from_edges(2, 700.0, 1e4, 2e4),
        Err(SignalError::BandAboveNyquist { .. })
    ));
    assert!(matches!(
        BandPass::from_edges(2, -1.0, 1e3, 2e4),
        Err(SignalError::InvalidParameter { .. })
    ));
}

// ---------------------------------------------------------------- chain

#[test]
fn default_chain_is_valid_and_documented() {
    let config = ChainConfig::default();
    let chain = SignalChain::new(config).unwrap();
    assert_eq!(chain, SignalChain::default());
    assert_eq!(chain.record_samples(), 1300);
    assert_eq!(chain.window(), 500..1300);
    assert!((chain.gain_at_f0() - 1.0).abs() < 1e-12);
    // The transient skip covers ≥ 25 time constants of the slowest pole.
    let rate = chain.filter().decay_rate();
    println!(
        "slowest decay rate {rate:.1} /s, skip = {:.1} τ",
        25e-3 * rate
    );
    assert!(25e-3 * rate > 25.0);
    // P43 nominal gain at 1 kHz.
    assert!((config.amplifier_gain_v_per_a - 94_088.26).abs() < 0.01);
    // Exact κ: a little below the asymptotic √(2/M) (the filter removes the
    // demodulator's far side lobes), by less than 3 %.
    let (k, k_inf) = (chain.noise_factor(), chain.asymptotic_noise_factor());
    println!(
        "noise factor κ = {k:.6e}, √(2/M) = {k_inf:.6e}, ratio {:.5}",
        k / k_inf
    );
    assert!((k_inf - 0.05).abs() < 1e-15);
    assert!(k < k_inf && k > 0.97 * k_inf);
}

#[test]
fn invalid_chain_parameters_are_typed_errors() {
    let base = ChainConfig::default();
    let err = |c: ChainConfig| SignalChain::new(c).unwrap_err();
    assert!(matches!(
        err(ChainConfig { f0_hz: 0.0, ..base }),
        SignalError::InvalidParameter { name: "f0_hz", .. }
    ));
    assert!(matches!(
        err(ChainConfig {
            f0_hz: -5.0,
            ..base
        }),
        SignalError::InvalidParameter { .. }
    ));
    assert!(matches!(
        err(ChainConfig {
            f0_hz: f64::NAN,
            ..base
        }),
        SignalError::InvalidParameter { .. }
    ));
    assert!(matches!(
        err(ChainConfig {
            bandwidth_hz: 2000.0,
            ..base
        }),
        SignalError::BandwidthTooWide { .. }
    ));
    assert!(matches!(
        err(ChainConfig {
            bandwidth_hz: 0.0,
            ..base
        }),
        SignalError::InvalidParameter { .. }
    ));
    assert!(matches!(
        err(ChainConfig { sample_rate_hz: 5000.0, ..base }),
        SignalError::SampleRateTooLow { minimum_hz, .. } if (minimum_hz - 5200.0).abs() < 1e-9
    ));
    assert!(matches!(
        err(ChainConfig {
            filter_order: 0,
            ..base
        }),
        SignalError::InvalidOrder { .. }
    ));
    assert!(matches!(
        err(ChainConfig {
            record_cycles: 20,
            transient_cycles: 20,
            ..base
        }),
        SignalError::RecordTooShort { .. }
    ));
    assert!(matches!(
        err(ChainConfig {
            record_cycles: 10_000_000,
            ..base
        }),
        SignalError::RecordTooLong { .. }
    ));
    assert!(matches!(
        err(ChainConfig {
            amplifier_gain_v_per_a: f64::INFINITY,
            ..base
        }),
        SignalError::InvalidParameter { .. }
    ));
    // Exactly at the minimum sample rate is accepted.
    assert!(SignalChain::new(ChainConfig {
        sample_rate_hz: 5200.0,
        ..base
    })
    .is_ok());

    let chain = SignalChain::default();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let amps = Amplitudes {
        vx1: 1.0,
        vx2: 1.0,
        vy1: 1.0,
        vy2: 1.0,
    };
    for snr in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert!(matches!(
            chain.measure(&amps, Some(snr), &mut rng),
            Err(SignalError::NonFiniteSnr { .. })
        ));
    }
    let bad = Amplitudes { vy1: -0.1, ..amps };
    assert!(matches!(
        chain.measure(&bad, Some(40.0), &mut rng),
        Err(SignalError::InvalidAmplitude { channel: "y1", .. })
    ));
    let bad = Amplitudes {
        vx2: f64::NAN,
        ..amps
    };
    assert!(matches!(
        chain.measure(&bad, None, &mut rng),
        Err(SignalError::InvalidAmplitude { channel: "x2", .. })
    ));
    assert!(matches!(
        chain.measure(&amps, Some(-2100.0), &mut rng),
        Err(SignalError::NoiseTooLarge { .. })
    ));
    assert!(matches!(
        chain.measure_channel(1.0, f64::NAN, None, &mut rng),
        Err(SignalError::InvalidParameter { .. })
    ));
    assert!(matches!(
        chain.demodulate(&[0.0; 10]),
        Err(SignalError::RecordLength {
            expected: 1300,
            found: 10
        })
    ));
    assert!(matches!(
        noise_sigma(1.0, f64::NAN),
        Err(SignalError::NonFiniteSnr { .. })
    ));
    // Extreme but valid inputs give finite numbers, never NaN.
    let huge = Amplitudes {
        vx1: 1e100,
        vx2: 0.0,
        vy1: 1e-300,
        vy2: 5e99,
    };
    let m = chain.measure(&huge, Some(20.0), &mut rng).unwrap();
    assert!([m.vx1, m.vx2, m.vy1, m.vy2]
        .iter()
        .all(|v| v.is_finite() && *v >= 0.0));
    let zero = Amplitudes {
        vx1: 0.0,
        vx2: 0.0,
        vy1: 0.0,
        vy2: 0.0,
    };
    assert_eq!(chain.measure(&zero, Some(30.0), &mut rng).unwrap(), zero);
}

#[test]
fn pure_sinusoid_is_recovered_exactly() {
    let amplitudes = [1e-6, 0.37, 1.0, 2.5, 1e4];
    let phases = [0.0, 0.3, 1.7, PI, 5.9, -2.0];
    let cases = [
        ("default (N = 2, 20 kHz)", ChainConfig::default(), 1e-9),
        (
            "order 1",
            ChainConfig {
                filter_order: 1,
                ..ChainConfig::default()
            },
            1e-9,
        ),
        (
            "50 kHz",
            ChainConfig {
                sample_rate_hz: 50_000.0,
                ..ChainConfig::default()
            },
            1e-9,
        ),
        (
            "order 4, longer skip",
            ChainConfig {
                filter_order: 4,
                record_cycles: 80,
                transient_cycles: 40,
                ..ChainConfig::default()
            },
            1e-9,
        ),
        (
            "arithmetic band edges",
            ChainConfig {
                band_placement: BandPlacement::Arithmetic,
                ..ChainConfig::default()
            },
            1e-9,
        ),
        // 22.05 samples a cycle: whole cycles are not whole samples; the
        // least-squares I/Q stays exact.
        (
            "non-integer samples per cycle",
            ChainConfig {
                sample_rate_hz: 22_050.0,
                ..ChainConfig::default()
            },
            1e-9,
        ),
        (
            "RMS",
            ChainConfig {
                demodulation: Demodulation::Rms,
                ..ChainConfig::default()
            },
            1e-6,
        ),
        (
            "RMS, order 1",
            ChainConfig {
                demodulation: Demodulation::Rms,
                filter_order: 1,
                ..ChainConfig::default()
            },
            1e-6,
        ),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    for (name, config, tol) in cases {
        let chain = chain(config);
        let mut worst: f64 = 0.0;
        for a in amplitudes {
            for phi in phases {
                let est = chain.measure_channel(a, phi, None, &mut rng).unwrap();
                worst = worst.max((est / a - 1.0).abs());
            }
        }
        println!("{name}: worst relative error {worst:.2e}");
        assert!(worst < tol, "{name}: {worst:e}");
    }
    // The 1e-9 needs the transient skip: without it the switch-on transient
    // spoils the estimate (shows the test can fail).
    let no_skip = chain(ChainConfig {
        transient_cycles: 0,
        ..ChainConfig::default()
    });
    let est = no_skip.measure_channel(1.0, 0.3, None, &mut rng).unwrap();
    assert!((est - 1.0).abs() > 1e-6, "{est}");
}

#[test]
fn synthesized_noise_has_the_requested_snr() {
    let chain = SignalChain::default();
    let fs = chain.config().sample_rate_hz;
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let mut record = Vec::new();
    for (v, snr) in [(0.8, 30.0), (0.05, 40.0), (3.0, 50.0)] {
        let expected = v * v / 2.0 / 10f64.powf(snr / 10.0);
        assert!((noise_sigma(v, snr).unwrap().powi(2) / expected - 1.0).abs() < 1e-12);
        let (mut sum, mut sum_sq, mut n) = (0.0, 0.0, 0usize);
        for r in 0..50 {
            let phi = 0.1 * r as f64;
            chain
                .synthesize(v, phi, Some(snr), &mut rng, &mut record)
                .unwrap();
            assert_eq!(record.len(), chain.record_samples());
            for (k, x) in record.iter().enumerate() {
                let e = x - v * (TAU * F0 * k as f64 / fs + phi).sin();
                sum += e;
                sum_sq += e * e;
                n += 1;
            }
        }
        let mean = sum / n as f64;
        let var = sum_sq / n as f64 - mean * mean;
        let tol = 5.0 * (2.0 / n as f64).sqrt();
        println!(
            "V {v} SNR {snr} dB: noise variance / σ² = {:.4} (n = {n}, tol {tol:.4})",
            var / expected
        );
        assert!(tol < 0.05);
        assert!((var / expected - 1.0).abs() < tol);
        assert!(mean.abs() < 5.0 * expected.sqrt() / (n as f64).sqrt());
        // The achieved SNR in dB.
        let snr_hat = 10.0 * ((v * v / 2.0) / var).log10();
        assert!((snr_hat - snr).abs() < 0.15);
    }
    // Without noise the record is the clean sinusoid.
    chain
        .synthesize(1.0, 0.5, None, &mut rng, &mut record)
        .unwrap();
    for (k, x) in record.iter().enumerate() {
        assert!((x - (TAU * F0 * k as f64 / fs + 0.5).sin()).abs() < 1e-12);
    }
}

/// Mean and sample standard deviation.
fn mean_std(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

#[test]
fn noisy_estimates_are_unbiased_with_the_theoretical_spread() {
    const N: usize = 2000;
    let clean = Amplitudes {
        vx1: 1.0,
        vx2: 0.25,
        vy1: 0.6,
        vy2: 2.0,
    };
    let std_tol = 4.0 / (2.0 * (N as f64 - 1.0)).sqrt();
    assert!(std_tol < 0.10);
    for method in [Demodulation::Iq, Demodulation::Rms] {
        let chain = chain(ChainConfig {
            demodulation: method,
            ..ChainConfig::default()
        });
        let nu = chain.filter().noise_gain();
        for snr in [30.0, 40.0, 50.0] {
            let mut rng = ChaCha8Rng::seed_from_u64(1000 + snr as u64);
            let mut samples: Vec<Vec<f64>> = (0..4).map(|_| Vec::with_capacity(N)).collect();
            for _ in 0..N {
                let m = chain.measure(&clean, Some(snr), &mut rng).unwrap();
                for (s, v) in samples.iter_mut().zip([m.vx1, m.vx2, m.vy1, m.vy2]) {
                    s.push(v);
                }
            }
            for (s, v) in samples
                .iter()
                .zip([clean.vx1, clean.vx2, clean.vy1, clean.vy2])
            {
                let (mean, std) = mean_std(s);
                let theory = chain.amplitude_std(v, snr).unwrap();
                let ratio = std / theory;
                // RMS: biased upwards by the noise power in the band,
                // σ² ν / V with ν the filter's noise gain (module docs).
                let expected_mean = match method {
                    Demodulation::Iq => v,
                    Demodulation::Rms => v + noise_sigma(v, snr).unwrap().powi(2) * nu / v,
                };
                let bias_z = (mean - expected_mean) / (theory / (N as f64).sqrt());
                println!(
                    "{method:?} SNR {snr} dB V {v}: std/theory = {ratio:.4}, relative std {:.3e}, \
                     bias = {bias_z:+.2} σ/√n",
                    std / v
                );
                assert!(
                    (ratio - 1.0).abs() < std_tol,
                    "{method:?} {snr} dB V {v}: std ratio {ratio}"
                );
                assert!(
                    bias_z.abs() < 4.0,
                    "{method:?} {snr} dB V {v}: bias {bias_z} σ/√n"
                );
            }
        }
    }
}

#[test]
fn theory_tracks_the_record_length() {
    // κ ∝ 1/√M: doubling the window divides the spread by √2, and the
    // empirical spread follows (shows the theory is not a constant).
    const N: usize = 2000;
    let long = chain(ChainConfig {
        record_cycles: 105,
        ..ChainConfig::default()
    });
    let short = SignalChain::default();
    let ratio_theory = short.noise_factor() / long.noise_factor();
    assert!((ratio_theory - 2f64.sqrt()).abs() < 0.02);
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    let xs: Vec<f64> = (0..N)
        .map(|_| {
            let phi = TAU * rng.random::<f64>();
            long.measure_channel(1.0, phi, Some(40.0), &mut rng)
                .unwrap()
        })
        .collect();
    let (_, std) = mean_std(&xs);
    let ratio = std / long.amplitude_std(1.0, 40.0).unwrap();
    assert!(
        (ratio - 1.0).abs() < 4.0 / (2.0 * (N as f64 - 1.0)).sqrt(),
        "{ratio}"
    );
}

#[test]
fn measure_channel_equals_synthesize_filter_demodulate() {
    for method in [Demodulation::Iq, Demodulation::Rms] {
        for order in [1, 2, 4] {
            let chain = chain(ChainConfig {
                demodulation: method,
                filter_order: order,
                ..ChainConfig::default()
            });
            let mut record = Vec::new();
            let mut worst: f64 = 0.0;
            for (seed, snr) in [(3, Some(35.0)), (4, None), (5, Some(0.0)), (6, Some(60.0))] {
                for (amplitude, phase) in [(0.7, 1.1), (2.0, -0.4), (1e-3, 3.0)] {
                    let mut a = ChaCha8Rng::seed_from_u64(seed);
                    let mut b = ChaCha8Rng::seed_from_u64(seed);
                    chain
                        .synthesize(amplitude, phase, snr, &mut a, &mut record)
                        .unwrap();
                    chain.filter().filter(&mut record);
                    let literal = chain.demodulate(&record).unwrap();
                    let measured = chain
                        .measure_channel(amplitude, phase, snr, &mut b)
                        .unwrap();
                    match method {
                        // Streaming: the same operations in the same order.
                        Demodulation::Rms => assert_eq!(literal.to_bits(), measured.to_bits()),
                        // By linearity: the same to rounding, relative to the
                        // signal plus noise level.
                        _ => {
                            let sigma = snr.map_or(0.0, |s| noise_sigma(amplitude, s).unwrap());
                            let err = (literal - measured).abs() / (amplitude + sigma);
                            worst = worst.max(err);
                        }
                    }
                    // Both consumed the same draws.
                    assert_eq!(a.random::<u64>(), b.random::<u64>());
                }
            }
            println!(
                "{method:?} order {order}: worst |literal − measured| / (A + σ) = {worst:.2e}"
            );
            assert!(worst < 1e-12, "{method:?} order {order}: {worst:e}");
        }
    }
}

#[test]
fn measure_is_deterministic_with_the_documented_draw_order() {
    let chain = SignalChain::default();
    let clean = Amplitudes {
        vx1: 0.3,
        vx2: 0.9,
        vy1: 0.5,
        vy2: 0.2,
    };
    let run = |seed| {
        chain
            .measure(&clean, Some(40.0), &mut ChaCha8Rng::seed_from_u64(seed))
            .unwrap()
    };
    let bits = |m: Amplitudes| [m.vx1, m.vx2, m.vy1, m.vy2].map(f64::to_bits);
    assert_eq!(bits(run(9)), bits(run(9)));
    let (a, b) = (run(9), run(10));
    for (x, y) in [
        (a.vx1, b.vx1),
        (a.vx2, b.vx2),
        (a.vy1, b.vy1),
        (a.vy2, b.vy2),
    ] {
        assert_ne!(x, y);
    }
    // Draw order: φ, then the four channel records x1, x2, y1, y2.
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let phi = TAU * rng.random::<f64>();
    let manual = [clean.vx1, clean.vx2, clean.vy1, clean.vy2]
        .map(|v| chain.measure_channel(v, phi, Some(40.0), &mut rng).unwrap());
    assert_eq!(bits(a), manual.map(f64::to_bits));
    // Without noise only φ is drawn.
    let mut r1 = ChaCha8Rng::seed_from_u64(2);
    chain.measure(&clean, None, &mut r1).unwrap();
    let mut r2 = ChaCha8Rng::seed_from_u64(2);
    let _: f64 = r2.random();
    assert_eq!(r1.random::<u64>(), r2.random::<u64>());
}

#[test]
fn measure_point_without_noise_returns_the_point() {
    let chain = SignalChain::default();
    let geometry = PsdGeometry::default();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let i0 = 20e-6;
    let mut worst: f64 = 0.0;
    for x in [-4.5, -3.1, -0.2, 0.0, 1.7, 4.0, 4.5] {
        for y in [-4.5, -2.2, 0.0, 0.9, 3.3, 4.5] {
            let p = Vector2::new(x, y);
            let (amps, m) = chain
                .measure_point(&geometry, &p, i0, &ChannelGains::UNIT, None, &mut rng)
                .unwrap();
            worst = worst.max((m - p).norm());
            let volts = i0 * chain.config().amplifier_gain_v_per_a;
            assert!((amps.total() / volts - 1.0).abs() < 1e-9);
        }
    }
    println!("measure_point, unit gains, no noise: worst error {worst:.2e} mm");
    assert!(worst < 1e-9);
}

#[test]
fn measure_point_with_gains_has_the_predicted_bias() {
    let chain = SignalChain::default();
    let geometry = PsdGeometry::default();
    let gains = ChannelGains {
        x2: 1.04,
        y1: 0.95,
        y2: 1.02,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let i0 = 20e-6;
    let volts = i0 * chain.config().amplifier_gain_v_per_a;
    for (x, y) in [(0.0, 0.0), (2.0, -1.0), (-3.5, 4.0)] {
        let p = Vector2::new(x, y);
        let (_, m) = chain
            .measure_point(&geometry, &p, i0, &gains, None, &mut rng)
            .unwrap();
        let predicted = impact_point(
            &geometry,
            &electrode_currents(&geometry, &p, volts).apply_gains(&gains),
        )
        .unwrap();
        assert!((m - predicted).norm() < 1e-9, "{m} vs {predicted}");
        // The bias is real (the test would catch ignored gains).
        assert!((m - p).norm() > 1e-2, "bias {}", (m - p).norm());
    }
    // With noise the point scatters around the biased point.
    const N: usize = 500;
    let p = Vector2::new(1.0, 2.0);
    let predicted = impact_point(
        &geometry,
        &electrode_currents(&geometry, &p, volts).apply_gains(&gains),
    )
    .unwrap();
    let pts: Vec<Vector2<f64>> = (0..N)
        .map(|_| {
            chain
                .measure_point(&geometry, &p, i0, &gains, Some(40.0), &mut rng)
                .unwrap()
                .1
        })
        .collect();
    for axis in 0..2 {
        let xs: Vec<f64> = pts.iter().map(|q| q[axis]).collect();
        let (mean, std) = mean_std(&xs);
        assert!(std > 0.0);
        assert!((mean - predicted[axis]).abs() < 4.0 * std / (N as f64).sqrt());
    }
}

#[test]
fn measure_point_errors_are_typed() {
    let chain = SignalChain::default();
    let geometry = PsdGeometry::default();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let p = Vector2::new(1.0, 1.0);
    let unit = ChannelGains::UNIT;
    assert!(matches!(
        chain.measure_point(&geometry, &p, 0.0, &unit, Some(40.0), &mut rng),
        Err(SignalError::NonPositiveTotal { .. })
    ));
    assert!(matches!(
        chain.measure_point(
            &geometry,
            &Vector2::new(5.0, 0.0),
            1e-5,
            &unit,
            None,
            &mut rng
        ),
        Err(SignalError::OffActiveArea { .. })
    ));
    assert!(matches!(
        chain.measure_point(
            &geometry,
            &Vector2::new(f64::NAN, 0.0),
            1e-5,
            &unit,
            None,
            &mut rng
        ),
        Err(SignalError::InvalidParameter { name: "point", .. })
    ));
    assert!(matches!(
        chain.measure_point(&geometry, &p, -1e-5, &unit, None, &mut rng),
        Err(SignalError::InvalidParameter { name: "i0", .. })
    ));
    let bad = ChannelGains { x2: 0.0, ..unit };
    assert!(matches!(
        chain.measure_point(&geometry, &p, 1e-5, &bad, None, &mut rng),
        Err(SignalError::Model(_))
    ));
    let flat = PsdGeometry { lx: 0.0, ly: 9.0 };
    assert!(matches!(
        chain.measure_point(&flat, &p, 1e-5, &unit, None, &mut rng),
        Err(SignalError::InvalidParameter { .. })
    ));
}

#[test]
fn chain_serialises_as_its_validated_configuration() {
    let chain = chain(ChainConfig {
        filter_order: 3,
        demodulation: Demodulation::Rms,
        ..ChainConfig::default()
    });
    let json = serde_json::to_string(&chain).unwrap();
    let back: SignalChain = serde_json::from_str(&json).unwrap();
    assert_eq!(back, chain);
    assert_eq!(
        back.noise_factor().to_bits(),
        chain.noise_factor().to_bits()
    );
    // Missing fields take their defaults; invalid ones are refused.
    let partial: SignalChain = serde_json::from_str(r#"{"sample_rate_hz": 50000.0}"#).unwrap();
    assert_eq!(partial.config().sample_rate_hz, 50_000.0);
    assert_eq!(
        partial.config().record_cycles,
        ChainConfig::default().record_cycles
    );
    assert!(serde_json::from_str::<SignalChain>(r#"{"sample_rate_hz": 3000.0}"#).is_err());
    assert!(serde_json::from_str::<SignalChain>(r#"{"unknown": 1}"#).is_err());
}
