//! A simulated room (psdcal-sim's `network_room`) as network data.
#![allow(dead_code)]

use nalgebra::Vector3;
use psdcal_model::{Model, Pose};
use psdcal_network::{Led, NetworkData, NetworkObservation, NetworkSensor};
use psdcal_sim::network_room::{NetworkRoom, NetworkRoomOptions, RoomLed};
use psdcal_sim::{ChainConfig, SignalChain};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

pub fn room(options: &NetworkRoomOptions, seed: u64) -> NetworkRoom {
    let chain = SignalChain::new(ChainConfig::default()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    NetworkRoom::simulate(options, &chain, &mut rng).unwrap()
}

pub fn data(room: &NetworkRoom, with_frame: bool) -> NetworkData {
    let frames = room.wand_poses.len();
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
        wand_names: (1..=room.wand.len()).map(|k| format!("w{k}")).collect(),
        frame_leds: if with_frame {
            room.frame_leds.clone()
        } else {
            vec![]
        },
        frame_names: if with_frame {
            (1..=room.frame_leds.len())
                .map(|k| format!("L{k}"))
                .collect()
        } else {
            vec![]
        },
        frames: (0..frames).map(|f| f.to_string()).collect(),
        observations: room
            .sightings
            .iter()
            .filter(|s| with_frame || matches!(s.led, RoomLed::Wand(_)))
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

/// The true `sensor_from_world` of sensor `k` in the calibration's world:
/// the room's with a static frame, else relative to sensor 0.
pub fn true_sensor_from_world(room: &NetworkRoom, k: usize, with_frame: bool) -> Pose {
    let s = room.sensors[k].world_from_sensor.inverse();
    if with_frame {
        s
    } else {
        s.compose(&room.sensors[0].world_from_sensor)
    }
}

pub fn rotation_error_deg(a: &Pose, b: &Pose) -> f64 {
    let r = a.rotation() * b.rotation().transpose();
    let c = ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
    c.acos().to_degrees()
}

pub fn centre(p: &Pose) -> Vector3<f64> {
    p.inverse().t
}
