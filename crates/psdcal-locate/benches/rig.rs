//! `locate --rig` at scale (issue 17): build a rig of n sensors and locate
//! n emitters, each seen by two neighbouring sensors. Near-linear in n: the
//! shared views are checked only for the pairs that observe together.
//!
//! `cargo bench -p psdcal-locate --bench rig`

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::{Vector2, Vector3};
use psdcal_locate::{
    measured_from_ray, CalibratedSensor, LocateOptions, Measurement, Rig, RigSensor,
};
use psdcal_model::{Pose, PsdGeometry, SensorModel};

/// Sensors every 100 mm along x, looking along +z.
fn sensors(n: usize) -> Vec<RigSensor> {
    let sensor = CalibratedSensor::new(SensorModel::paper_lens2(), PsdGeometry::default());
    (0..n)
        .map(|k| RigSensor {
            id: format!("s{k}"),
            sensor: sensor.clone(),
            world_from_sensor: Pose::new(
                Vector3::zeros(),
                Vector3::new(100.0 * k as f64, 0.0, 0.0),
            ),
        })
        .collect()
}

/// Emitter k at 2 m, between sensors k and k + 1, as both measure it.
fn observations(rig: &Rig) -> Vec<Vec<(usize, Measurement)>> {
    let model = psdcal_model::Model::standard(&SensorModel::paper_lens2());
    (0..rig.sensors().len() - 1)
        .map(|k| {
            let emitter = Vector3::new(100.0 * k as f64 + 50.0, 30.0, 2000.0);
            [k, k + 1]
                .iter()
                .map(|&i| {
                    let p = rig.sensors()[i]
                        .world_from_sensor
                        .inverse()
                        .transform(&emitter);
                    let m = measured_from_ray(&model, &Vector2::new(p.x / p.z, p.y / p.z))
                        .expect("in view");
                    (i, Measurement::Point(m))
                })
                .collect()
        })
        .collect()
}

fn locate_all(c: &mut Criterion) {
    let mut group = c.benchmark_group("rig");
    group.sample_size(10);
    for n in [400, 2000] {
        let template = Rig::new(sensors(n)).expect("a valid rig");
        let seen = observations(&template);
        group.bench_with_input(BenchmarkId::new("new_and_locate", n), &n, |b, &n| {
            b.iter(|| {
                let rig = Rig::new(sensors(n)).expect("a valid rig");
                let options = LocateOptions::default();
                let located = seen
                    .iter()
                    .filter(|obs| rig.locate(obs, &options).is_ok())
                    .count();
                assert_eq!(located, n - 1);
            })
        });
    }
    group.finish();
}

criterion_group!(benches, locate_all);
criterion_main!(benches);
