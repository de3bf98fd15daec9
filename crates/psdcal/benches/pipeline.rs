//! The whole `psdcal calibrate` process on files, in process: load and
//! validate the data set (template.csv, observations.csv), calibrate from
//! automatic initialisation (start, solve, covariance, statistics, the
//! record with its provenance and residuals), write calibration.json
//! atomically (what `psdcal calibrate -t T -o O --out X -q` does, less the
//! process start and argument parsing).
//!
//! The data set is written once: the paper's lens 2 simulated through the
//! signal chain at 40 dB per channel, 12 images of the 14-LED template
//! (`psdcal::simulate_files`, as `psdcal simulate` writes it).

use criterion::{criterion_group, criterion_main, Criterion};
use psdcal::{
    calibrate, simulate_files, CalibrationOptions, DataSet, DataSetFiles, Lens, LoadOptions,
    PointSource, SimulateRequest, TemplateKind, DEFAULT_RECORD_CYCLES,
};
use std::hint::black_box;

fn pipeline(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temporary folder");
    let data = dir.path().join("data");
    simulate_files(&SimulateRequest {
        lens: Lens::Two,
        snr_db: Some(40.0),
        imbalance: false,
        psd_distortion: false,
        psd_nonlinearity: false,
        images: 12,
        template: TemplateKind::Scatter14,
        record_cycles: DEFAULT_RECORD_CYCLES,
        seed: 1,
        out: data.clone(),
        force: false,
    })
    .expect("simulated data set");
    let files = DataSetFiles {
        template: data.join("template.csv"),
        points: PointSource::Observations(data.join("observations.csv")),
        gains: None,
    };
    let out = dir.path().join("calibration.json");
    let options = CalibrationOptions::default();
    let mut group = c.benchmark_group("pipeline");
    group.bench_function("calibrate files 12x14", |b| {
        b.iter(|| {
            let set = DataSet::from_files(black_box(&files), &LoadOptions::default()).unwrap();
            let mut calibrated = calibrate(&set, &options).unwrap();
            calibrated.set_command("psdcal calibrate (bench)");
            calibrated.write(&set, &out, None).unwrap();
        })
    });
    group.finish();
    assert!(out.exists());
}

criterion_group!(benches, pipeline);
criterion_main!(benches);
