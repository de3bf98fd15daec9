//! A rig's shared-view check applies each sensor's whole model, its PSD map
//! included. Two pinhole sensors (f = 8 mm, 9 mm active area: ray tangents
//! within ±0.5625, ±29.4°) at the same place, the second turned 60° about
//! y: world direction angle `β + atan t`, so without a map the second sees
//! 30.6°…89.4° and the two views miss each other by 1.2°. A map that shifts
//! every measured point by a constant `s` in x (`m' = m + s`) moves the
//! second's ideal range to `[−4.5 + s, 4.5 + s]` mm: `s = −4` gives
//! tangents −1.0625…0.0625, angles 13.3°…63.6° (shared with the first);
//! `s = +4` gives 56.4°…106.7° (not shared).

use nalgebra::Vector3;
use psdcal_locate::{CalibratedSensor, Rig, RigSensor, SensorPsdMap};
use psdcal_model::stages::{MapBasis, MapFrame, PsdMap};
use psdcal_model::{Pose, PsdGeometry, SensorModel, Stage};

fn constant_shift(s: f64) -> SensorPsdMap {
    let stage = PsdMap::new(
        MapBasis::Polynomial { order: 0 },
        MapFrame::centred(9.0, 9.0),
        None,
    )
    .unwrap();
    let block = stage
        .parameters()
        .iter()
        .map(|p| if p.name.starts_with("map_x") { s } else { 0.0 })
        .collect();
    SensorPsdMap { stage, block }
}

fn rig(shift: Option<f64>) -> Rig {
    let model = SensorModel::pinhole(8.0, 0.0, 0.0);
    let plain = CalibratedSensor::new(model, PsdGeometry::default());
    let turned = match shift {
        Some(s) => plain.clone().with_psd_map(constant_shift(s)),
        None => plain.clone(),
    };
    Rig::new(vec![
        RigSensor {
            id: "a".into(),
            sensor: plain,
            world_from_sensor: Pose::new(Vector3::zeros(), Vector3::zeros()),
        },
        RigSensor {
            id: "b".into(),
            sensor: turned,
            world_from_sensor: Pose::new(
                Vector3::new(0.0, 60f64.to_radians(), 0.0),
                Vector3::zeros(),
            ),
        },
    ])
    .unwrap()
}

#[test]
fn the_shared_view_follows_the_psd_map() {
    assert!(!rig(None).shares_view(0, 1), "no map: the views miss");
    assert!(!rig(Some(0.0)).shares_view(0, 1), "a zero map: the same");
    assert!(
        rig(Some(-4.0)).shares_view(0, 1),
        "the map turns the view towards the first sensor"
    );
    assert!(!rig(Some(4.0)).shares_view(0, 1), "the map turns it away");
}

#[test]
fn the_constant_map_is_seen_in_the_angles() {
    // Independent check of the convention the test relies on: with the
    // map, the measured point −4 mm reads as the ideal point −8 mm, a ray
    // tangent of −1.
    let sensor = CalibratedSensor::new(SensorModel::pinhole(8.0, 0.0, 0.0), PsdGeometry::default())
        .with_psd_map(constant_shift(-4.0));
    let est = sensor
        .aoa(
            &psdcal_locate::Measurement::Point(nalgebra::Vector2::new(-4.0, 0.0)),
            &psdcal_locate::LocateOptions::default(),
        )
        .unwrap();
    assert!((est.aoa.ray_ab.x + 1.0).abs() < 1e-12, "{}", est.aoa.ray_ab);
}
