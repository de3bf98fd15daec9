//! The positioning room (psdcal-sim's `room`): the layout, emitters seen by
//! every sensor inside the margin, noise-free observations that back-project
//! onto the emitter, determinism and refused layouts.

use nalgebra::Vector3;
use psdcal_model::{Model, PsdGeometry, SensorModel};
use psdcal_sim::room::{observe_emitter, true_impact, Room, RoomOptions, RoomSensor};
use psdcal_sim::{SignalChain, SimError};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn room(seed: u64, options: &RoomOptions) -> Result<Room, SimError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    Room::draw(
        options,
        &SensorModel::paper_lens2(),
        &PsdGeometry::default(),
        &mut rng,
    )
}

#[test]
fn layout_and_emitters_follow_the_options() {
    let options = RoomOptions::default();
    let r = room(1, &options).unwrap();
    assert_eq!(r.sensors.len(), 2);
    assert_eq!(r.emitters.len(), 100);
    assert!((r.sensors[0].t - Vector3::new(500.0, 0.0, 2500.0)).norm() < 1e-9);
    assert!((r.sensors[1].t - Vector3::new(-500.0, 0.0, 2500.0)).norm() < 1e-9);
    // Looking down: the optical axis is world −z.
    let axis = r.sensors[0].rotation() * Vector3::z();
    assert!((axis + Vector3::z()).norm() < 1e-12);
    let truth = Model::standard(&SensorModel::paper_lens2());
    let g = PsdGeometry::default();
    for e in &r.emitters {
        assert_eq!(e.z, 0.0);
        for s in &r.sensors {
            let m = true_impact(&truth, &g, s, e, options.margin).unwrap();
            assert!(m.x.abs() <= 0.4 * g.lx && m.y.abs() <= 0.4 * g.ly);
        }
    }
    assert_eq!(r, room(1, &options).unwrap());
    assert_ne!(r, room(2, &options).unwrap());
}

#[test]
fn noise_free_observations_back_project_onto_the_emitter() {
    let r = room(5, &RoomOptions::default()).unwrap();
    let truth = Model::standard(&SensorModel::paper_lens2());
    let g = PsdGeometry::default();
    let chain = SignalChain::default();
    let sensor = RoomSensor {
        truth: &truth,
        geometry: &g,
        chain: &chain,
        i0: 20e-6,
        snr_db: None,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for e in r.emitters.iter().take(20) {
        for s in &r.sensors {
            let o = observe_emitter(&sensor, s, e, &mut rng).unwrap();
            assert!((o.measured - o.true_measured).norm() < 1e-9, "{o:?}");
            let ray = s.rotation() * truth.direction(&o.true_measured).into_inner();
            let to_emitter = e - s.t;
            let miss = (to_emitter - ray * to_emitter.dot(&ray)).norm();
            assert!(miss < 1e-6, "miss {miss} mm");
        }
    }
}

#[test]
fn impossible_rooms_are_refused() {
    let two = RoomOptions {
        sensors: 1,
        ..RoomOptions::default()
    };
    assert!(matches!(room(1, &two), Err(SimError::Options(_))));
    let far = RoomOptions {
        baseline_mm: 20_000.0,
        ..RoomOptions::default()
    };
    let e = room(1, &far).unwrap_err();
    assert!(e.to_string().contains("shorten the baseline"), "{e}");
}
