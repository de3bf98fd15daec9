//! Refinement speed: the paper's size (9 images × 14 LEDs), noise-weighted,
//! with l1 freed
//! (global search), and a large set (10 to 1000 images × 20 LEDs) to show the
//! cost per image stays flat (Schur complement on the pose blocks); and the
//! whole calibration from automatic initialisation.
//!
//! The issue "One engine" asks for the start, the solve and the whole
//! calibration separately, on 12 images × 14 LEDs of lens 2 at the point
//! noise the paper's 40 dB chain produces (about 0.3 µm per coordinate,
//! tests/refine.rs): `start/12x14` (`initialize` only), `solve/12x14`
//! (`refine` from that start, as `calibrate` runs it), `calibrate/12x14`
//! (start, solve, covariance, statistics, diagnostics) and
//! `calibrate/1000x20`; `diagnose/12x14` is the diagnostics alone (their
//! share of `calibrate/12x14`).

#[path = "../tests/support/mod.rs"]
mod support;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use psdcal_calib::{
    calibrate, initialize, refine, refine_global, CalibrateOptions, GlobalOptions, NoiseModel,
    RefineOptions,
};
use psdcal_model::{Model, Param, SensorModel};
use std::hint::black_box;

fn paper_size(c: &mut Criterion) {
    let truth = SensorModel::paper_lens2();
    let s = support::scenario(truth, 9, 3e-4, 1);
    let (m0, p0) = support::perturbed(&truth, &s.poses);
    let options = RefineOptions::default();
    c.bench_function("refine 9x14 lens2 f,cx,cy,k1,k2", |b| {
        b.iter(|| refine(black_box(&s.data), m0, &p0, &options).unwrap())
    });
    // Noise-weighted (per-channel SNR): whitening plus reweighting passes.
    let weighted = RefineOptions {
        noise: NoiseModel::ChannelSnr,
        ..RefineOptions::default()
    };
    c.bench_function("refine 9x14 lens2 channel-snr weighted", |b| {
        b.iter(|| refine(black_box(&s.data), m0, &p0, &weighted).unwrap())
    });
    let mut truth_psd = truth;
    truth_psd.distortion.l1 = SensorModel::PAPER_L1;
    let s = support::scenario(truth_psd, 9, 3e-4, 1);
    let (mut m0, p0) = support::perturbed(&truth_psd, &s.poses);
    m0.distortion.l1 = 0.0;
    let options = RefineOptions {
        free: vec![
            Param::F,
            Param::Cx,
            Param::Cy,
            Param::K1,
            Param::K2,
            Param::L1,
        ],
        ..RefineOptions::default()
    };
    let global = GlobalOptions::default();
    c.bench_function("refine_global 9x14 lens2 +l1", |b| {
        b.iter(|| refine_global(black_box(&s.data), m0, &p0, &options, &global).unwrap())
    });
}

fn scaling(c: &mut Criterion) {
    let truth = SensorModel::paper_lens2();
    let mut group = c.benchmark_group("refine x20 LEDs");
    group.sample_size(10);
    for n in [10usize, 100, 1000] {
        let s = support::scenario_with(truth, 20, n, 3e-4, 2);
        let (m0, p0) = support::perturbed(&truth, &s.poses);
        let options = RefineOptions::default();
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| refine(black_box(&s.data), m0, &p0, &options).unwrap())
        });
    }
    group.finish();
}

/// The whole calibration from automatic initialisation (preliminary
/// correction, homographies, closed form and its check, refinement,
/// covariance, statistics).
fn end_to_end(c: &mut Criterion) {
    let truth = SensorModel::paper_lens2();
    let s = support::scenario(truth, 9, 3e-4, 1);
    let options = CalibrateOptions::default();
    c.bench_function("calibrate 9x14 lens2", |b| {
        b.iter(|| calibrate(black_box(&s.data), &options).unwrap())
    });
    let mut group = c.benchmark_group("calibrate x20 LEDs");
    group.sample_size(10);
    for n in [10usize, 1000] {
        let s = support::scenario_with(truth, 20, n, 3e-4, 2);
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| calibrate(black_box(&s.data), &options).unwrap())
        });
    }
    group.finish();
}

/// Point noise per coordinate equivalent to the paper's 40 dB chain, mm.
const SIGMA_40DB_MM: f64 = 3e-4;

/// The three parts of the figures: the start, the solve from it and
/// the whole library calibration (12 × 14, lens 2), and the whole
/// calibration at 1000 × 20.
fn start_solve_calibrate(c: &mut Criterion) {
    let truth = SensorModel::paper_lens2();
    let s = support::scenario(truth, 12, SIGMA_40DB_MM, 12);
    let options = CalibrateOptions::default();
    let mut group = c.benchmark_group("start");
    group.bench_function("12x14", |b| {
        b.iter(|| initialize(black_box(&s.data), &options.init).unwrap())
    });
    group.finish();
    // The refinement's start as `calibrate` builds it: `base` with the
    // freed parameters the initialisation estimates.
    let init = initialize(&s.data, &options.init).unwrap();
    let mut start: Model = options.base.clone();
    for p in &options.refine.free {
        start
            .set(p.name(), init.model.get(p.name()).unwrap())
            .unwrap();
    }
    let mut group = c.benchmark_group("solve");
    group.bench_function("12x14", |b| {
        b.iter(|| refine(black_box(&s.data), &start, &init.poses, &options.refine).unwrap())
    });
    group.finish();
    let mut group = c.benchmark_group("calibrate");
    group.bench_function("12x14", |b| {
        b.iter(|| calibrate(black_box(&s.data), &options).unwrap())
    });
    group.finish();
    let r = calibrate(&s.data, &options).unwrap();
    let refined = r.refined();
    let mut group = c.benchmark_group("diagnose");
    group.bench_function("12x14", |b| {
        b.iter(|| {
            psdcal_calib::diagnose(
                black_box(&s.data),
                &refined,
                &options.refine,
                &r.covariance,
                r.global.as_ref(),
                &options.diagnostics,
            )
        })
    });
    group.finish();
    let mut group = c.benchmark_group("calibrate");
    group.sample_size(10);
    let large = support::scenario_with(truth, 20, 1000, SIGMA_40DB_MM, 2);
    group.throughput(Throughput::Elements(1000));
    group.bench_function("1000x20", |b| {
        b.iter(|| calibrate(black_box(&large.data), &options).unwrap())
    });
    group.finish();
}

criterion_group!(
    benches,
    paper_size,
    scaling,
    end_to_end,
    start_solve_calibrate
);
criterion_main!(benches);
