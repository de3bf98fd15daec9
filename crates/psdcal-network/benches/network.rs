//! The whole network calibration (start without a guess, bundle
//! adjustment, covariance, diagnostics) of a simulated room of 8 sensors
//! with a 3-LED wand and a static frame: 3 000 frames (60 s at 50 Hz) and
//! 30 000 frames (600 s), to show the time linear in frames.

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{criterion_group, criterion_main, Criterion};
use psdcal_network::{calibrate_network, NetworkOptions};
use psdcal_sim::network_room::NetworkRoomOptions;

fn network(c: &mut Criterion) {
    let mut group = c.benchmark_group("calibrate_network");
    group.sample_size(10);
    for seconds in [60.0, 600.0] {
        let options = NetworkRoomOptions {
            duration_s: seconds,
            ..NetworkRoomOptions::default()
        };
        let d = common::data(&common::room(&options, 1), true);
        group.bench_function(format!("8_sensors_{}_frames", d.frames.len()), |b| {
            b.iter(|| calibrate_network(&d, &NetworkOptions::default()).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, network);
criterion_main!(benches);
