//! The whole network calibration (start without a guess, bundle
//! adjustment, covariance, diagnostics) of a simulated room of 8 sensors
//! with a 3-LED wand and a static frame: 3 000 frames (60 s at 50 Hz) and
//! 30 000 frames (600 s), to show the time linear in frames.

use criterion::{criterion_group, criterion_main, Criterion};
use psdcal_model::Model;
use psdcal_network::{
    calibrate_network, Led, NetworkData, NetworkObservation, NetworkOptions, NetworkSensor,
};
use psdcal_sim::network_room::{NetworkRoom, NetworkRoomOptions, RoomLed};
use psdcal_sim::{ChainConfig, SignalChain};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn data(seconds: f64) -> NetworkData {
    let chain = SignalChain::new(ChainConfig::default()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let options = NetworkRoomOptions {
        duration_s: seconds,
        ..NetworkRoomOptions::default()
    };
    let room = NetworkRoom::simulate(&options, &chain, &mut rng).unwrap();
    NetworkData {
        sensors: room
            .sensors
            .iter()
            .enumerate()
            .map(|(k, s)| NetworkSensor {
                id: format!("s{}", k + 1),
                model: Model::standard(&s.lab),
                prior_names: s.lab_params.iter().map(|p| p.name().to_string()).collect(),
                prior_covariance: s.lab_covariance.clone(),
                geometry: room.geometry,
            })
            .collect(),
        wand: room.wand.clone(),
        wand_names: vec!["w1".into(), "w2".into(), "w3".into()],
        frame_leds: room.frame_leds.clone(),
        frame_names: (1..=room.frame_leds.len())
            .map(|k| format!("L{k}"))
            .collect(),
        frames: (0..room.wand_poses.len()).map(|f| f.to_string()).collect(),
        observations: room
            .sightings
            .iter()
            .map(|s| NetworkObservation {
                frame: s.frame,
                sensor: s.sensor,
                led: match s.led {
                    RoomLed::Wand(k) => Led::Wand(k),
                    RoomLed::Frame(k) => Led::Frame(k),
                },
                measured: s.measured,
            })
            .collect(),
    }
}

fn network(c: &mut Criterion) {
    let mut group = c.benchmark_group("calibrate_network");
    group.sample_size(10);
    for seconds in [60.0, 600.0] {
        let d = data(seconds);
        group.bench_function(format!("8_sensors_{}_frames", d.frames.len()), |b| {
            b.iter(|| calibrate_network(&d, &NetworkOptions::default()).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, network);
criterion_main!(benches);
