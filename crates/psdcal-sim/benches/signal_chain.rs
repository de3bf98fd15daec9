//! Timing of the signal chain at its defaults (docs/model.md §6): one channel
//! record (1300 samples: synthesis with noise, order-2 band-pass, I/Q
//! demodulation) and one full point (four channels and the impact point).
//! A study runs ~10⁴ trials × 126 points × 4 channels of these.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Vector2;
use psdcal_model::{Amplitudes, ChannelGains, PsdGeometry};
use psdcal_sim::signal::{ChainConfig, Demodulation, SignalChain};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn bench_chain(c: &mut Criterion) {
    let chain = SignalChain::default();
    let rms = SignalChain::new(ChainConfig {
        demodulation: Demodulation::Rms,
        ..ChainConfig::default()
    })
    .expect("valid configuration");
    let mut rng = ChaCha8Rng::seed_from_u64(1);

    c.bench_function("channel record, 40 dB (I/Q)", |b| {
        b.iter(|| chain.measure_channel(black_box(0.5), black_box(0.3), Some(40.0), &mut rng))
    });
    c.bench_function("channel record, 40 dB (RMS)", |b| {
        b.iter(|| rms.measure_channel(black_box(0.5), black_box(0.3), Some(40.0), &mut rng))
    });
    c.bench_function("channel record, no noise", |b| {
        b.iter(|| chain.measure_channel(black_box(0.5), black_box(0.3), None, &mut rng))
    });

    let clean = Amplitudes {
        vx1: 0.3,
        vx2: 0.6,
        vy1: 0.5,
        vy2: 0.4,
    };
    c.bench_function("four channels (measure), 40 dB", |b| {
        b.iter(|| chain.measure(black_box(&clean), Some(40.0), &mut rng))
    });

    let geometry = PsdGeometry::default();
    let gains = ChannelGains {
        x2: 1.01,
        y1: 0.99,
        y2: 1.02,
    };
    let point = Vector2::new(1.2, -0.8);
    c.bench_function("point (measure_point), 40 dB", |b| {
        b.iter(|| {
            chain.measure_point(
                &geometry,
                black_box(&point),
                20e-6,
                &gains,
                Some(40.0),
                &mut rng,
            )
        })
    });

    c.bench_function("chain construction (default)", |b| {
        b.iter(|| SignalChain::new(black_box(ChainConfig::default())))
    });
}

criterion_group!(benches, bench_chain);
criterion_main!(benches);
