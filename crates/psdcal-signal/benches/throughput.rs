//! Samples per second through the band-pass and the lock-in detection
//! (docs/model.md §8): the streaming filter alone, the filter plus I/Q sums
//! against the tone's reference, and a whole record's demodulation (filter,
//! frequency estimate, joint fit, noise) for one channel and for four.

use std::f64::consts::TAU;
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use psdcal_signal::butterworth::BandPass;
use psdcal_signal::lockin::window_sums;
use psdcal_signal::tones::{fill_reference, project_frames};
use psdcal_signal::{demodulate_record, DemodConfig, StreamFilter};

const FS: f64 = 20_000.0;
const N: usize = 200_000;

fn signal(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| {
            0.7 * (TAU * 1000.0 * i as f64 / FS + 0.3).sin()
                + 0.01 * ((i * 7919) % 101) as f64 / 101.0
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let filter = BandPass::centred(2, 1000.0, 600.0, FS).unwrap();
    let x = signal(N);
    let (mut cos, mut sin) = (vec![0.0; N], vec![0.0; N]);
    let mut group = c.benchmark_group("signal");
    group.throughput(Throughput::Elements(N as u64));
    group.bench_function("band-pass, 1 channel", |b| {
        let mut buf = x.clone();
        b.iter(|| {
            buf.copy_from_slice(&x);
            let mut stream = StreamFilter::<1>::new(filter.clone());
            stream.process_channel(0, &mut buf);
            black_box(buf[N - 1])
        })
    });
    group.bench_function("band-pass + I/Q detection, 1 channel", |b| {
        let mut buf = x.clone();
        b.iter(|| {
            buf.copy_from_slice(&x);
            let mut stream = StreamFilter::<1>::new(filter.clone());
            stream.process_channel(0, &mut buf);
            fill_reference(1000.0, FS, 0, &mut cos, &mut sin);
            black_box(window_sums(&buf, &cos, &sin))
        })
    });
    let config = DemodConfig::default();
    let frames1: Vec<[f64; 1]> = x.iter().map(|&v| [v]).collect();
    group.bench_function("demodulate record, 1 channel", |b| {
        b.iter(|| demodulate_record(black_box(&frames1), FS, &[1000.0], &config).unwrap())
    });
    let frames4: Vec<[f64; 4]> = x.iter().map(|&v| [v, 0.5 * v, 0.3 * v, 0.8 * v]).collect();
    group.throughput(Throughput::Elements(4 * N as u64));
    group.bench_function("band-pass, 4 channels (channel-samples)", |b| {
        let mut buf = frames4.clone();
        b.iter(|| {
            buf.copy_from_slice(&frames4);
            let mut stream = StreamFilter::<4>::new(filter.clone());
            stream.process_frames(&mut buf);
            black_box(buf[N - 1])
        })
    });
    group.bench_function("I/Q projection, 4 channels (channel-samples)", |b| {
        b.iter(|| project_frames(1000.0, FS, 0, black_box(&frames4)))
    });
    group.bench_function("demodulate record, 4 channels (channel-samples)", |b| {
        b.iter(|| demodulate_record(black_box(&frames4), FS, &[1000.0], &config).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
