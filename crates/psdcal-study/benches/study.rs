//! One study trial of each kind: simulate nine images through the signal
//! chain and calibrate (Tables 3–10), or compute the closed form (Tables 1–2).

use criterion::{criterion_group, criterion_main, Criterion};
use psdcal_study::{table_spec, StudyOptions};
use std::hint::black_box;

fn trials(c: &mut Criterion) {
    let options = StudyOptions::default();
    let mut group = c.benchmark_group("study trial");
    group.sample_size(20);
    for (id, column) in [
        ("table2", 3),
        ("table3", 1),
        ("table4", 1),
        ("table4", 4),
        ("table6", 0),
        ("table8", 3),
    ] {
        let spec = table_spec(id).unwrap();
        let condition = spec.columns[column].clone();
        let name = format!("{id} {}", condition.label);
        let mut k = 0u64;
        group.bench_function(name, |b| {
            b.iter(|| {
                k += 1;
                psdcal_study::study::run_trial(black_box(&condition), &options, k)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, trials);
criterion_main!(benches);
