//! Fitting a 41 × 41 scan (auto: every candidate cross-validated, and
//! spline:8 alone) and applying a fitted map to a million points.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Vector2;
use psdcal_model::stages::MapBasis;
use psdcal_model::Stage;
use psdcal_psdmap::{fit_psd_map, FitOptions, ModelChoice};

/// A 41 × 41 raster over ±4.5 mm with a smooth field of ≈ 100 µm and a
/// deterministic ±0.5 µm jitter.
fn scan() -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
    let mut stage = Vec::new();
    let mut measured = Vec::new();
    for i in 0..41 {
        for j in 0..41 {
            let m = Vector2::new(-4.5 + 0.225 * i as f64, -4.5 + 0.225 * j as f64);
            let (u, v) = (m.x / 4.5, m.y / 4.5);
            let d = Vector2::new(
                0.06 * u * u * u + 0.03 * u * v * v + 0.01 * (3.0 * v).sin(),
                0.08 * v * v * v + 0.02 * u * u * v,
            );
            let jitter = Vector2::new(
                (((i * 7 + j * 13) % 11) as f64 - 5.0) * 1e-4,
                (((i * 3 + j * 5) % 7) as f64 - 3.0) * 1.5e-4,
            );
            stage.push(m + d + jitter);
            measured.push(m);
        }
    }
    (stage, measured)
}

fn bench(c: &mut Criterion) {
    let (stage, measured) = scan();
    let mut group = c.benchmark_group("psd_map");
    group.sample_size(10);
    group.bench_function("fit/41x41/auto", |b| {
        b.iter(|| {
            fit_psd_map(
                black_box(&stage),
                black_box(&measured),
                &FitOptions::default(),
            )
        })
    });
    let spline = FitOptions {
        model: ModelChoice::Fixed(MapBasis::Spline {
            cells_x: 8,
            cells_y: 8,
        }),
        ..FitOptions::default()
    };
    group.bench_function("fit/41x41/spline8", |b| {
        b.iter(|| fit_psd_map(black_box(&stage), black_box(&measured), &spline))
    });
    let points: Vec<Vector2<f64>> = (0..1_000_000)
        .map(|k| {
            let t = k as f64 * 0.618_033_988_75;
            Vector2::new(
                4.4 * (t.fract() * 2.0 - 1.0),
                4.4 * ((t * 1.7).fract() * 2.0 - 1.0),
            )
        })
        .collect();
    for (name, basis) in [
        (
            "apply/1M/spline8",
            MapBasis::Spline {
                cells_x: 8,
                cells_y: 8,
            },
        ),
        ("apply/1M/poly7", MapBasis::Polynomial { order: 7 }),
    ] {
        let fit = fit_psd_map(
            &stage,
            &measured,
            &FitOptions {
                model: ModelChoice::Fixed(basis),
                ..FitOptions::default()
            },
        )
        .expect("fit");
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut sum = Vector2::zeros();
                for p in &points {
                    sum += fit.map.apply(&fit.block, black_box(p), None);
                }
                sum
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
