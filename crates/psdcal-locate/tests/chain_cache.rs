//! A sensor builds its chains once and reuses them point after point; its
//! fields are public, so an answer after a change of any of them must be
//! the answer of a sensor built with the new values (never the old chain's).

use nalgebra::Vector2;
use psdcal_locate::{CalibratedSensor, LocateOptions, Measurement};
use psdcal_model::{ChannelGains, ParameterCovariance, PsdGeometry, SensorModel};

fn answer(sensor: &CalibratedSensor) -> (f64, f64, f64) {
    let at = Measurement::Point(Vector2::new(1.2, -0.7));
    let a = sensor.aoa(&at, &LocateOptions::default()).unwrap();
    let c = a.ray_covariance_calibration;
    (a.aoa.ray_ab.x, a.aoa.ray_ab.y, c[(0, 0)] + c[(1, 1)])
}

fn covariance(names: &[&str], sigma: f64) -> ParameterCovariance {
    let n = names.len();
    let rows: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| if i == j { sigma * sigma } else { 0.0 })
                .collect()
        })
        .collect();
    ParameterCovariance::from_named(names, &rows).unwrap()
}

#[test]
fn an_answer_follows_every_change_of_the_sensor() {
    let mut sensor = CalibratedSensor::new(SensorModel::paper_lens2(), PsdGeometry::default());
    sensor.covariance = covariance(&["f", "cx", "cy"], 1e-3);
    let first = answer(&sensor);
    assert_eq!(answer(&sensor), first, "the same sensor, the same answer");

    let fresh = |model: SensorModel, cov: ParameterCovariance| {
        let mut s = CalibratedSensor::new(model, PsdGeometry::default());
        s.covariance = cov;
        s
    };
    let mut model = SensorModel::paper_lens2();
    model.intrinsics.f *= 1.01;
    sensor.model = model;
    let changed = answer(&sensor);
    assert_ne!(changed, first);
    assert_eq!(
        changed,
        answer(&fresh(model, covariance(&["f", "cx", "cy"], 1e-3)))
    );

    sensor.covariance = covariance(&["f", "cx", "cy", "k1"], 2e-3);
    assert_eq!(
        answer(&sensor),
        answer(&fresh(model, covariance(&["f", "cx", "cy", "k1"], 2e-3)))
    );
    // A copy answers as the original, whatever the original's cache held.
    let copy = sensor.clone();
    assert_eq!(copy, sensor);
    assert_eq!(answer(&copy), answer(&sensor));
    // Gains change the chain's parameters (amplitude input).
    sensor.gains = Some(ChannelGains::UNIT);
    assert_eq!(answer(&sensor), answer(&copy));
}
