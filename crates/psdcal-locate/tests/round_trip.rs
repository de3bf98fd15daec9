//! Acceptance: emitter position → measured point → located position within
//! 1e-9 mm, for both lenses (with and without PSD distortion), on a plane
//! parallel to the sensor, on a tilted plane, from electrode amplitudes
//! through unbalanced gains, and for a rig of three sensors.

mod support;

use nalgebra::{Vector2, Vector3};
use psdcal_locate::{CalibratedSensor, LocateOptions, Measurement, Plane};
use psdcal_model::psd::electrode_currents;
use psdcal_model::{ChannelGains, PsdGeometry};
use support::{measure, models, three_sensor_rig};

const TOL_MM: f64 = 1e-9;

/// Emitters on `plane` whose rays cover the sensor: the rays through a
/// 7 × 7 grid of ideal points within ±3.8 mm of the optical centre.
fn emitters_on(plane: &Plane, model: &psdcal_model::SensorModel) -> Vec<Vector3<f64>> {
    let mut out = Vec::new();
    for iy in 0..7 {
        for ix in 0..7 {
            let a = (-3.8 + 7.6 * ix as f64 / 6.0) / model.intrinsics.f;
            let b = (-3.8 + 7.6 * iy as f64 / 6.0) / model.intrinsics.f;
            let r = Vector3::new(a, b, 1.0);
            let s = plane.offset_mm() / plane.normal().dot(&r);
            out.push(r * s);
        }
    }
    out
}

#[test]
fn plane_round_trips_for_both_lenses() {
    let mut worst: f64 = 0.0;
    for (name, model) in models() {
        let sensor = CalibratedSensor::new(model, PsdGeometry::default());
        let planes = [
            Plane::parallel(1000.0).unwrap(),
            Plane::parallel(5000.0).unwrap(),
            Plane::new(Vector3::new(0.2, -0.3, 1.0), 4000.0).unwrap(),
        ];
        for plane in &planes {
            for emitter in emitters_on(plane, &model) {
                let m = measure(&model, &emitter);
                let at = sensor
                    .locate_on_plane(&Measurement::Point(m), plane, &LocateOptions::default())
                    .unwrap();
                let e = (at.intersection.position - emitter).norm();
                worst = worst.max(e);
                assert!(
                    e < TOL_MM,
                    "{name}: emitter {emitter:?} located {e:e} mm away"
                );
            }
        }
    }
    println!("plane round trips: worst {worst:.2e} mm");
}

#[test]
fn amplitude_round_trip_through_unbalanced_gains() {
    let geometry = PsdGeometry::default();
    let gains = ChannelGains {
        x2: 1.021,
        y1: 0.987,
        y2: 1.004,
    };
    let plane = Plane::parallel(5000.0).unwrap();
    for (name, model) in models() {
        let sensor = CalibratedSensor::new(model, geometry).with_gains(gains);
        for emitter in emitters_on(&plane, &model) {
            let m = measure(&model, &emitter);
            let amps = electrode_currents(&geometry, &m, 2.5e-6).apply_gains(&gains);
            let at = sensor
                .locate_on_plane(
                    &Measurement::Amplitudes(amps),
                    &plane,
                    &LocateOptions::default(),
                )
                .unwrap();
            let e = (at.intersection.position - emitter).norm();
            assert!(e < TOL_MM, "{name}: {e:e} mm");
        }
    }
}

#[test]
fn rig_of_three_sensors_round_trips() {
    let mut worst: f64 = 0.0;
    for (name, model) in models() {
        let rig = three_sensor_rig(model);
        assert_eq!(rig.view_pairs(), vec![(0, 1), (0, 2), (1, 2)], "{name}");
        // Emitters on and above the floor near the point the sensors look at.
        for ix in -2..=2 {
            for iy in -2..=2 {
                for z in [0.0, 300.0] {
                    let emitter = Vector3::new(100.0 * ix as f64, 80.0 * iy as f64, z);
                    let seen: Vec<(usize, Measurement)> = rig
                        .sensors()
                        .iter()
                        .enumerate()
                        .map(|(k, s)| {
                            let p = s.world_from_sensor.inverse().transform(&emitter);
                            (k, Measurement::Point(measure(&model, &p)))
                        })
                        .collect();
                    for subset in [&seen[..], &seen[..2], &seen[1..]] {
                        let at = rig.locate(subset, &LocateOptions::default()).unwrap();
                        let e = (at.triangulation.position - emitter).norm();
                        worst = worst.max(e);
                        assert!(e < TOL_MM, "{name}: emitter {emitter:?}: {e:e} mm");
                        assert!(at.triangulation.miss_mm.iter().all(|d| *d < TOL_MM));
                        assert!(at.cautions.is_empty(), "{:?}", at.cautions);
                    }
                }
            }
        }
    }
    println!("rig round trips: worst {worst:.2e} mm");
}

#[test]
fn paper_parallel_plane_formula() {
    // X = S tan αx, Y = S tan αy exactly, with the angles from the full model.
    for (_, model) in models() {
        let sensor = CalibratedSensor::new(model, PsdGeometry::default());
        let plane = Plane::parallel(5000.0).unwrap();
        for m in support::sensor_points() {
            let at = sensor
                .locate_on_plane(&Measurement::Point(m), &plane, &LocateOptions::default())
                .unwrap();
            let alpha = at.aoa.aoa.alpha;
            let expected = Vector2::new(5000.0 * alpha.x.tan(), 5000.0 * alpha.y.tan());
            let got = at.intersection.position.xy();
            assert!((got - expected).norm() < 1e-9, "{got:?} vs {expected:?}");
        }
    }
}
