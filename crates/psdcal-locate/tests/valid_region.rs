//! Issue 12's reproducer: a calibration whose correction folds inside the
//! active area (k1 = −0.02 mm⁻² about (0.5, −0.7) on a 9 mm sensor) never
//! answers past the fold — angle of arrival, position on a plane, rig and
//! error map — while a non-folding calibration answers exactly as before.

mod support;

use nalgebra::{Vector2, Vector3};
use psdcal_locate::{
    angle_of_arrival, error_map, CalibratedSensor, ErrorSource, LocateError, LocateOptions,
    MapOptions, Measurement, ParameterCovariance, ParameterErrors, Plane, Rig, RigSensor,
};
use psdcal_model::{Param, Pose, PsdGeometry, SensorModel};

fn folding() -> SensorModel {
    let mut m = SensorModel::pinhole(8.0, 0.5, -0.7);
    m.distortion.k1 = -0.02;
    m
}

/// The fold radius of `r ↦ r (1 + k1 r²)`: `det = (1 + 3 k1 r²)(1 + k1 r²)`
/// first vanishes at `r* = 1/√(3 |k1|)` = 4.082 mm.
fn fold_radius() -> f64 {
    1.0 / (3.0f64 * 0.02).sqrt()
}

const CORNER: Vector2<f64> = Vector2::new(-4.5, 4.5);

fn is_past_fold(e: &LocateError) -> bool {
    e.status() == "outside_valid_region"
        && matches!(
            e,
            LocateError::BeyondValidRegion {
                end: psdcal_model::RegionEnd::Fold,
                ..
            }
        )
}

#[test]
fn the_corner_past_the_fold_is_never_ok() {
    let model = folding();
    // The per-point check alone answers the corner: its determinant is
    // positive again and its ideal point is mirrored through the centre.
    let bare = angle_of_arrival(&psdcal_model::Model::standard(&model), &CORNER).unwrap();
    let c = Vector2::new(0.5, -0.7);
    assert!((bare.ideal - c).dot(&(CORNER - c)) < 0.0);
    let sensor = CalibratedSensor::new(model, PsdGeometry::default());
    let options = LocateOptions::default();
    let e = sensor
        .aoa(&Measurement::Point(CORNER), &options)
        .unwrap_err();
    assert!(is_past_fold(&e), "{e}");
    let LocateError::BeyondValidRegion {
        distance_mm,
        limit_mm,
        ..
    } = e
    else {
        unreachable!()
    };
    assert!((distance_mm - 52.04f64.sqrt()).abs() < 1e-12);
    assert!((limit_mm - fold_radius() * (1.0 - 1e-3)).abs() < 1e-9);
    assert!(e.to_string().contains("folds over"), "{e}");
    let plane = Plane::parallel(5000.0).unwrap();
    let e = sensor
        .locate_on_plane(&Measurement::Point(CORNER), &plane, &options)
        .unwrap_err();
    assert!(is_past_fold(&e), "{e}");
    // Just inside the fold along the same direction: answered.
    let inside = c + (CORNER - c).normalize() * fold_radius() * 0.99;
    assert!(sensor.aoa(&Measurement::Point(inside), &options).is_ok());
    // Amplitudes whose point is the corner: refused too.
    let a = psdcal_model::psd::electrode_currents(&PsdGeometry::default(), &CORNER, 1.0);
    let e = sensor
        .aoa(&Measurement::Amplitudes(a), &options)
        .unwrap_err();
    assert!(is_past_fold(&e), "{e}");
}

#[test]
fn a_rig_refuses_an_observation_past_a_fold() {
    let sensor = |id: &str, x: f64, model| RigSensor {
        id: id.into(),
        sensor: CalibratedSensor::new(model, PsdGeometry::default()),
        world_from_sensor: Pose::new(Vector3::zeros(), Vector3::new(x, 0.0, 0.0)),
    };
    let rig = Rig::new(vec![
        sensor("plain", -500.0, SensorModel::paper_lens2()),
        sensor("folding", 500.0, folding()),
    ])
    .unwrap();
    let seen = [
        (0, Measurement::Point(Vector2::new(1.0, 0.5))),
        (1, Measurement::Point(CORNER)),
    ];
    let e = rig.locate(&seen, &LocateOptions::default()).unwrap_err();
    assert!(is_past_fold(&e), "{e}");
}

#[test]
fn error_map_cells_past_the_fold_have_no_values() {
    let geometry = PsdGeometry::default();
    let options = MapOptions {
        grid: 21,
        ..MapOptions::default()
    };
    let errors = ParameterErrors::new(vec![(Param::F, 0.1)]).unwrap();
    let cov = ParameterCovariance::from_params(
        &[Param::Cx],
        &nalgebra::DMatrix::from_element(1, 1, 1e-4),
    )
    .unwrap();
    let c = Vector2::new(0.5, -0.7);
    for source in [
        ErrorSource::Parameters(errors),
        ErrorSource::Covariance {
            covariance: cov,
            k: 2.0,
        },
    ] {
        let map = error_map(&folding(), &geometry, &source, &options).unwrap();
        let mut refused = 0;
        for cell in &map.cells {
            // Cells well clear of the fold circle (beyond the 1e-3 margin
            // and the 1° ray spacing) are decided by the closed form.
            let r = (cell.measured - c).norm();
            if r < fold_radius() * 0.99 {
                assert!(cell.values.is_ok(), "{:?}", cell.measured);
            } else if r > fold_radius() * 1.001 {
                let e = cell.values.as_ref().unwrap_err();
                assert!(is_past_fold(e), "{:?}: {e}", cell.measured);
                refused += 1;
            }
        }
        assert!(refused > 100, "{refused}");
    }
}

#[test]
fn non_folding_sensors_answer_as_before() {
    for (name, model) in support::models() {
        let sensor = CalibratedSensor::new(model, PsdGeometry::default());
        assert!(sensor.valid_region.whole_active_area(), "{name}");
        for p in support::sensor_points()
            .into_iter()
            .chain([Vector2::new(4.5, -4.5), Vector2::new(4.8, 0.0)])
        {
            let est = sensor
                .aoa(&Measurement::Point(p), &LocateOptions::default())
                .unwrap();
            assert_eq!(
                est.aoa,
                angle_of_arrival(&psdcal_model::Model::standard(&model), &p).unwrap(),
                "{name} {p:?}"
            );
        }
    }
}
