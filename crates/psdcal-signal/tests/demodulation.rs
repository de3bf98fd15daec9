//! The demodulation of one record (docs/model.md §8) against independent
//! references: exact amplitudes of noise-free sinusoids (one tone, several
//! tones, a clock offset), the noise floor `σ √(2/M)` of a least-squares
//! detector over `M` samples (white noise of variance `σ²` at rate `fs` has
//! the one-sided density `2σ²/fs`; averaging over `T = M/fs` passes
//! `2σ²/M` to each quadrature), with and without a card's impairments,
//! and the typed refusals.

#![allow(clippy::needless_range_loop)] // channel-indexed loops read as the equations

use std::f64::consts::TAU;

use psdcal_signal::butterworth::BandPass;
use psdcal_signal::tones::check_separable;
use psdcal_signal::{demodulate_record, DemodConfig, SignalError, StreamFilter};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

const FS: f64 = 20_000.0;

/// `Σ_k A_{k,c} sin(2π f_k t + φ_k)` on four channels, `len` samples.
fn tones_record(len: usize, fs: f64, tones: &[(f64, [f64; 4], f64)]) -> Vec<[f64; 4]> {
    (0..len)
        .map(|n| {
            let t = n as f64 / fs;
            let mut frame = [0.0; 4];
            for &(f, amps, phase) in tones {
                let s = (TAU * f * t + phase).sin();
                for c in 0..4 {
                    frame[c] += amps[c] * s;
                }
            }
            frame
        })
        .collect()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn chunked_filtering_equals_whole_filtering() {
    let filter = BandPass::centred(2, 1000.0, 600.0, FS).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let x: Vec<f64> = (0..5000).map(|_| rng.sample(StandardNormal)).collect();
    let mut whole = x.clone();
    filter.filter(&mut whole);
    for trial in 0..20 {
        let mut stream = StreamFilter::<1>::new(filter.clone());
        let mut chunked = x.clone();
        let mut start = 0;
        while start < chunked.len() {
            let size = if trial == 0 {
                1
            } else {
                rng.random_range(1..700)
            };
            let end = (start + size).min(chunked.len());
            stream.process_channel(0, &mut chunked[start..end]);
            start = end;
        }
        assert_eq!(chunked, whole, "trial {trial}");
    }
    // Frames: every channel as if filtered alone.
    let frames: Vec<[f64; 4]> = (0..3000)
        .map(|_| std::array::from_fn(|_| rng.sample(StandardNormal)))
        .collect();
    let mut stream = StreamFilter::<4>::new(filter.clone());
    let mut out = frames.clone();
    for chunk in out.chunks_mut(333) {
        stream.process_frames(chunk);
    }
    for c in 0..4 {
        let mut alone: Vec<f64> = frames.iter().map(|f| f[c]).collect();
        filter.filter(&mut alone);
        let got: Vec<f64> = out.iter().map(|f| f[c]).collect();
        assert_eq!(got, alone, "channel {c}");
    }
}

#[test]
fn noise_free_amplitudes_are_exact() {
    let config = DemodConfig::default();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    // Integer and non-integer samples per cycle, short and long records.
    for (fs, f0, len) in [
        (FS, 1000.0, 1300),
        (19_997.0, 1000.0, 1500),
        (50_000.0, 1234.5, 9000),
    ] {
        for _ in 0..5 {
            let amps: [f64; 4] = std::array::from_fn(|_| rng.random_range(0.01..3.0));
            let phase = rng.random_range(0.0..TAU);
            let rec = tones_record(len, fs, &[(f0, amps, phase)]);
            let est = demodulate_record(&rec, fs, &[f0], &config).unwrap();
            let tone = &est.tones[0];
            for c in 0..4 {
                assert!(
                    rel(tone.amplitudes[c], amps[c]) < 1e-12,
                    "fs {fs} f0 {f0}: {} vs {}",
                    tone.amplitudes[c],
                    amps[c]
                );
            }
            assert!(rel(tone.frequency_hz, f0) < 1e-12, "{}", tone.frequency_hz);
            // The residual of a noise-free fit is rounding (~1e-8 of the
            // amplitude after the cancellation in Σy² − θᵀb): SNR ≳ 120 dB.
            assert!(tone.min_snr_db() > 110.0, "{}", tone.min_snr_db());
            assert!(!tone.dark);
        }
    }
}

#[test]
fn noise_free_tones_are_separated_exactly() {
    let config = DemodConfig::default();
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let freqs = [800.0, 900.0, 1000.0, 1130.0];
    let tones: Vec<(f64, [f64; 4], f64)> = freqs
        .iter()
        .map(|&f| {
            (
                f,
                std::array::from_fn(|_| rng.random_range(0.05..2.0)),
                rng.random_range(0.0..TAU),
            )
        })
        .collect();
    let rec = tones_record(4000, FS, &tones);
    let est = demodulate_record(&rec, FS, &freqs, &config).unwrap();
    for (tone, (f, amps, _)) in est.tones.iter().zip(&tones) {
        assert_eq!(tone.nominal_hz, *f);
        for c in 0..4 {
            assert!(
                rel(tone.amplitudes[c], amps[c]) < 1e-12,
                "{f} Hz channel {c}: {} vs {}",
                tone.amplitudes[c],
                amps[c]
            );
        }
    }
}

#[test]
fn a_clock_offset_is_estimated_and_removed() {
    let config = DemodConfig::default();
    let amps = [1.0, 0.5, 0.25, 2.0];
    for ppm in [-80.0, -30.0, 25.0, 60.0] {
        let f_true = 1000.0 * (1.0 + ppm * 1e-6);
        let rec = tones_record(1300, FS, &[(f_true, amps, 0.4)]);
        let est = demodulate_record(&rec, FS, &[1000.0], &config).unwrap();
        let tone = &est.tones[0];
        assert!(
            // The estimate stops once a pass moves the tone by < 1e-7
            // cycles over the window (≤ 2.5e-6 Hz here); it lands far closer.
            (tone.frequency_hz - f_true).abs() < 1e-8,
            "{ppm} ppm: {} vs {f_true}",
            tone.frequency_hz
        );
        for c in 0..4 {
            assert!(rel(tone.amplitudes[c], amps[c]) < 1e-11, "{ppm} ppm");
        }
        // Several tones share the clock ratio.
        let freqs = [900.0, 1000.0, 1100.0];
        let tones: Vec<_> = freqs
            .iter()
            .map(|&f| (f * (1.0 + ppm * 1e-6), amps, 1.0))
            .collect();
        let rec = tones_record(6000, FS, &tones);
        let est = demodulate_record(&rec, FS, &freqs, &config).unwrap();
        assert!(
            (est.clock_ratio - (1.0 + ppm * 1e-6)).abs() < 1e-9,
            "{}",
            est.clock_ratio
        );
        for tone in &est.tones {
            for c in 0..4 {
                assert!(
                    // The joint fit at the estimated ratio (its error ~2e-11)
                    // leaves ~5e-11 of cross-talk: exactness needs exact
                    // clocks (the previous tests).
                    rel(tone.amplitudes[c], amps[c]) < 1e-9,
                    "{ppm} ppm: {} vs {}",
                    tone.amplitudes[c],
                    amps[c]
                );
            }
        }
    }
}

/// Impairments a card adds besides white noise (all off: none).
#[derive(Clone, Copy)]
struct Impairments {
    dc: f64,
    hum: f64,
    drift_v_per_s: f64,
    quantise: bool,
}

/// RMS error of the amplitudes over seeded records against the floor
/// `σ √(2/M)`, and the mean reported σ_Â and SNR.
fn noise_floor_ratio(snr_db: f64, tones: &[f64], imp: Impairments, seed: u64) -> (f64, f64, f64) {
    let config = DemodConfig::default();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let amps = [1.2, 0.8, 0.6, 1.0];
    let len = if tones.len() == 1 { 1300 } else { 4000 };
    let (mut sq, mut n, mut reported, mut snr_sum, mut window) = (0.0, 0.0, 0.0, 0.0, 0);
    let lsb = 20.0 / 65536.0;
    for _ in 0..250 {
        let spec: Vec<_> = tones
            .iter()
            .map(|&f| (f, amps, rng.random_range(0.0..TAU)))
            .collect();
        let mut rec = tones_record(len, FS, &spec);
        let hum_phase: f64 = rng.random_range(0.0..TAU);
        for (i, frame) in rec.iter_mut().enumerate() {
            let t = i as f64 / FS;
            for (c, x) in frame.iter_mut().enumerate() {
                let sigma = amps[c] * 10f64.powf(-snr_db / 20.0) / 2f64.sqrt();
                let e: f64 = rng.sample(StandardNormal);
                *x += sigma * e
                    + imp.dc
                    + imp.drift_v_per_s * t
                    + imp.hum
                        * ((TAU * 50.0 * t + hum_phase).sin()
                            + 0.3 * (TAU * 150.0 * t).sin()
                            + 0.1 * (TAU * 250.0 * t).sin());
                if imp.quantise {
                    *x = (*x / lsb).round() * lsb;
                }
            }
        }
        let est = demodulate_record(&rec, FS, tones, &config).unwrap();
        window = est.window.len();
        for tone in &est.tones {
            for c in 0..4 {
                let sigma = amps[c] * 10f64.powf(-snr_db / 20.0) / 2f64.sqrt();
                let floor = sigma * (2.0 / window as f64).sqrt();
                sq += ((tone.amplitudes[c] - amps[c]) / floor).powi(2);
                reported += tone.amplitude_std[c] / floor;
                snr_sum += tone.snr_db[c];
                n += 1.0;
            }
        }
    }
    assert!(window > 100);
    ((sq / n).sqrt(), reported / n, snr_sum / n)
}

#[test]
fn errors_sit_on_the_theoretical_noise_floor() {
    let off = Impairments {
        dc: 0.0,
        hum: 0.0,
        drift_v_per_s: 0.0,
        quantise: false,
    };
    let on = Impairments {
        dc: 2.5,
        hum: 0.05,
        drift_v_per_s: 0.3,
        quantise: true,
    };
    for (k, snr_db) in [30.0, 40.0, 50.0].into_iter().enumerate() {
        for (label, imp) in [("clean", off), ("impaired", on)] {
            for tones in [&[1000.0][..], &[850.0, 1000.0, 1150.0][..]] {
                let (ratio, reported, snr) = noise_floor_ratio(snr_db, tones, imp, 100 + k as u64);
                // 1000 or 3000 estimates: the RMS ratio's sampling error is
                // ≤ 2.3 %; the bound is 10 %.
                assert!(
                    (ratio - 1.0).abs() < 0.1,
                    "{snr_db} dB {label} {tones:?}: error / floor = {ratio}"
                );
                // Hum leaking through the band-pass counts as noise in the
                // residual: the reported σ may only err upwards with the
                // impairments on (conservative), by at most 40 %.
                let high = if label == "clean" { 0.1 } else { 0.4 };
                assert!(
                    reported > 0.9 && reported < 1.0 + high,
                    "{snr_db} dB {label} {tones:?}: reported σ / floor = {reported}"
                );
                let low = if label == "clean" {
                    0.5
                } else {
                    20.0 * 1.4f64.log10()
                };
                assert!(
                    snr < snr_db + 0.5 && snr > snr_db - low,
                    "{snr_db} dB {label} {tones:?}: reported SNR {snr}"
                );
            }
        }
    }
}

#[test]
fn refusals_are_typed() {
    let config = DemodConfig::default();
    let rec = tones_record(1300, FS, &[(1000.0, [1.0; 4], 0.0)]);
    assert!(matches!(
        demodulate_record(&rec[..500], FS, &[1000.0], &config),
        Err(SignalError::RecordTooShortToDemodulate { samples: 500, .. })
    ));
    assert!(matches!(
        demodulate_record::<4>(&rec, FS, &[], &config),
        Err(SignalError::NoTones)
    ));
    let mut clipped = rec.clone();
    clipped[700][2] = 10.0;
    assert!(matches!(
        demodulate_record(&clipped, FS, &[1000.0], &config),
        Err(SignalError::Saturated {
            channel: 2,
            sample: 700,
            ..
        })
    ));
    let mut nan = rec.clone();
    nan[3][1] = f64::NAN;
    assert!(matches!(
        demodulate_record(&nan, FS, &[1000.0], &config),
        Err(SignalError::NonFiniteSample {
            channel: 1,
            sample: 3
        })
    ));
    // 1300 samples leave a ~37 ms window: tones 40 Hz apart are separable,
    // 30 Hz apart are not.
    let est = demodulate_record(&rec, FS, &[1000.0, 1060.0], &config);
    assert!(est.is_ok(), "{est:?}");
    let err = demodulate_record(&rec, FS, &[1000.0, 1030.0], &config).unwrap_err();
    assert!(
        matches!(err, SignalError::TonesNotSeparable { .. }),
        "{err}"
    );
    assert!(err.to_string().contains("2 / window"), "{err}");
    assert!(check_separable(&[1000.0, 1000.0], FS, 1.0).is_err());
    assert!(check_separable(&[1000.0, 1002.0], FS, 1.0).is_ok());
    for bad in [f64::NAN, -1.0, 15_000.0] {
        assert!(
            demodulate_record(&rec, FS, &[bad], &config).is_err(),
            "{bad}"
        );
    }
    assert!(demodulate_record(&rec, f64::NAN, &[1000.0], &config).is_err());
}

#[test]
fn dark_only_when_the_total_light_is() {
    let config = DemodConfig::default();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let noise = |rec: &mut Vec<[f64; 4]>, rng: &mut ChaCha8Rng| {
        for frame in rec.iter_mut() {
            for x in frame.iter_mut() {
                *x += 1e-3 * rng.sample::<f64, _>(StandardNormal);
            }
        }
    };
    for _ in 0..20 {
        let mut dark = vec![[0.0; 4]; 1300];
        noise(&mut dark, &mut rng);
        assert!(
            demodulate_record(&dark, FS, &[1000.0], &config)
                .unwrap()
                .tones[0]
                .dark
        );
        // One channel without light, the others lit: not dark.
        let mut lit = tones_record(1300, FS, &[(1000.0, [0.0, 0.05, 0.05, 0.05], 0.3)]);
        noise(&mut lit, &mut rng);
        let est = demodulate_record(&lit, FS, &[1000.0], &config).unwrap();
        assert!(!est.tones[0].dark);
        assert!(est.tones[0].snr_db[0] < 10.0);
    }
    let zero = vec![[0.0; 4]; 1300];
    let est = demodulate_record(&zero, FS, &[1000.0], &config).unwrap();
    assert!(est.tones[0].dark);
    assert!(est.tones[0].snr_db.iter().all(|s| s.is_finite()));
}
