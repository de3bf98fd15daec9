//! `psdcal export`'s work: OpenCV's rational model fitted to the paper's
//! lens 2 over the valid region (41 × 41 points) with its error on 101 × 101,
//! and the two-calibration comparison on a 41 × 41 grid.

use criterion::{criterion_group, criterion_main, Criterion};
use psdcal_locate::{
    diff_calibrations, fit_opencv, CalibratedSensor, CameraFitOptions, OpenCvKind,
};
use psdcal_model::{PsdGeometry, SensorModel};

fn benches(c: &mut Criterion) {
    let sensor = CalibratedSensor::new(SensorModel::paper_lens2(), PsdGeometry::default());
    let options = CameraFitOptions::default();
    c.bench_function("fit_opencv/rational/lens2", |b| {
        b.iter(|| fit_opencv(&sensor, OpenCvKind::Rational, &options).unwrap())
    });
    let other = CalibratedSensor::new(SensorModel::paper_lens1(), PsdGeometry::default());
    c.bench_function("diff/41x41", |b| {
        b.iter(|| diff_calibrations(&sensor, &other, 41).unwrap())
    });
}

criterion_group!(group, benches);
criterion_main!(group);
