//! Inputs that cannot be answered give typed errors with a status code, and
//! answers that deserve care carry a caution — never a NaN.

mod support;

use nalgebra::{DMatrix, Matrix2, Vector2, Vector3};
use psdcal_locate::{
    angle_of_arrival, error_map, intersect_plane, triangulate, CalibratedSensor, Caution,
    ErrorSource, LocateError, LocateOptions, MapOptions, Measurement, ParameterCovariance,
    ParameterErrors, Plane, Rig, RigSensor, WorldRay,
};
use psdcal_model::{Amplitudes, Param, Pose, PsdGeometry, SensorModel};

/// A PSD distortion strong enough to fold over inside the 9 mm area:
/// `s = 1 + l1 h²` has `∂(s·h)/∂h = 0` at `h² = 1/(3|l1|) ≈ 16.7 mm²`.
fn folding_model() -> SensorModel {
    let mut m = SensorModel::paper_lens1();
    m.distortion.l1 = -0.02;
    m
}

#[test]
fn points_outside_the_valid_region() {
    let model = folding_model();
    let e = angle_of_arrival(
        &psdcal_model::Model::standard(&model),
        &Vector2::new(4.5, 4.5),
    )
    .unwrap_err();
    assert_eq!(e.status(), "outside_valid_region", "{e}");
    assert!(e.to_string().contains("folds over"), "{e}");
    assert!(angle_of_arrival(
        &psdcal_model::Model::standard(&model),
        &Vector2::new(1.0, 1.0)
    )
    .is_ok());
    let e = angle_of_arrival(
        &psdcal_model::Model::standard(&SensorModel::paper_lens2()),
        &Vector2::new(1e300, 0.0),
    )
    .unwrap_err();
    assert_eq!(e.status(), "outside_valid_region", "{e}");
    let e = angle_of_arrival(
        &psdcal_model::Model::standard(&model),
        &Vector2::new(f64::NAN, 0.0),
    )
    .unwrap_err();
    assert_eq!(e.status(), "non_finite_input");
    let mut bad = model;
    bad.intrinsics.f = 0.0;
    let e = angle_of_arrival(&psdcal_model::Model::standard(&bad), &Vector2::zeros()).unwrap_err();
    assert_eq!(e.status(), "model_error");
}

#[test]
fn amplitudes_without_light() {
    let sensor = CalibratedSensor::new(SensorModel::paper_lens2(), PsdGeometry::default());
    let dark = Amplitudes {
        vx1: 0.0,
        vx2: 0.0,
        vy1: 0.0,
        vy2: 0.0,
    };
    let e = sensor
        .aoa(&Measurement::Amplitudes(dark), &LocateOptions::default())
        .unwrap_err();
    assert_eq!(e.status(), "no_light");
}

#[test]
fn off_area_points_are_answered_with_a_caution() {
    let sensor = CalibratedSensor::new(SensorModel::paper_lens2(), PsdGeometry::default());
    let est = sensor
        .aoa(
            &Measurement::Point(Vector2::new(4.8, 0.0)),
            &LocateOptions::default(),
        )
        .unwrap();
    assert!(est.off_active_area);
    assert_eq!(est.cautions()[0].status(), "off_active_area");
    let options = LocateOptions {
        point_sigma_mm: -1.0,
        ..LocateOptions::default()
    };
    let e = sensor
        .aoa(&Measurement::Point(Vector2::zeros()), &options)
        .unwrap_err();
    assert_eq!(e.status(), "invalid_input");
}

#[test]
fn rays_that_miss_the_plane() {
    // The plane x = 100 mm (a wall to the sensor's right).
    let wall = Plane::new(Vector3::new(1.0, 0.0, 0.0), 100.0).unwrap();
    let e = intersect_plane(&wall, &Vector2::new(0.0, 0.3)).unwrap_err();
    assert_eq!(e.status(), "parallel_to_plane", "{e}");
    let e = intersect_plane(&wall, &Vector2::new(-0.1, 0.0)).unwrap_err();
    assert_eq!(e.status(), "points_away_from_plane", "{e}");
    assert!(matches!(e, LocateError::PointsAwayFromPlane { distance_mm } if distance_mm < 0.0));
    let hit = intersect_plane(&wall, &Vector2::new(0.1, 0.0)).unwrap();
    assert!((hit.position.x - 100.0).abs() < 1e-12);
    // Grazing: the ray meets the wall at about 5.7°.
    let sensor = CalibratedSensor::new(SensorModel::paper_lens2(), PsdGeometry::default());
    let m = psdcal_locate::measured_from_ray(
        &psdcal_model::Model::standard(&sensor.model),
        &Vector2::new(0.1, 0.0),
    )
    .unwrap();
    let at = sensor
        .locate_on_plane(&Measurement::Point(m), &wall, &LocateOptions::default())
        .unwrap();
    assert!(
        matches!(at.cautions[..], [Caution::GrazingPlane { angle_deg }] if (angle_deg - 5.71).abs() < 0.01)
    );
    // Planes through the sensor or with a zero normal are refused.
    assert_eq!(
        Plane::new(Vector3::z(), 0.0).unwrap_err().status(),
        "invalid_input"
    );
    assert!(Plane::parallel(-5.0).is_err());
    assert!(Plane::new(Vector3::new(f64::NAN, 0.0, 1.0), 1.0).is_err());
}

fn ray(x_mm: f64, ab: (f64, f64)) -> WorldRay {
    WorldRay {
        sensor: format!("at {x_mm}"),
        world_from_sensor: Pose::new(Vector3::zeros(), Vector3::new(x_mm, 0.0, 0.0)),
        ray_ab: Vector2::new(ab.0, ab.1),
        covariance_ab: Matrix2::identity() * 1e-8,
    }
}

#[test]
fn degenerate_triangulations() {
    let o = LocateOptions::default();
    let e = triangulate(&[ray(0.0, (0.0, 0.0))], &o).unwrap_err();
    assert_eq!(e.status(), "too_few_sensors");
    let e = triangulate(&[ray(-500.0, (0.1, 0.0)), ray(500.0, (0.1, 0.0))], &o).unwrap_err();
    assert_eq!(e.status(), "parallel_rays", "{e}");
    // Diverging rays meet behind the sensors.
    let e = triangulate(&[ray(-500.0, (-0.2, 0.0)), ray(500.0, (0.2, 0.0))], &o).unwrap_err();
    assert_eq!(e.status(), "behind_sensor", "{e}");
    // Nearly parallel: 1000 mm baseline, emitter 30 m away (1.9°).
    let emitter = Vector3::new(0.0, 0.0, 30_000.0);
    let rays = [-500.0, 500.0].map(|x| {
        let p = emitter - Vector3::new(x, 0.0, 0.0);
        ray(x, (p.x / p.z, p.y / p.z))
    });
    let t = triangulate(&rays, &o).unwrap();
    assert!((t.position - emitter).norm() < 1e-6);
    assert!(
        matches!(t.cautions[..], [Caution::NearlyParallelRays { angle_deg }] if angle_deg < 2.0)
    );
    // NaN anywhere is refused.
    let mut bad = rays.clone();
    bad[0].ray_ab.x = f64::NAN;
    assert_eq!(
        triangulate(&bad, &o).unwrap_err().status(),
        "non_finite_input"
    );
}

#[test]
fn rig_without_a_shared_view() {
    let model = SensorModel::paper_lens1();
    let sensor = |id: &str, pose: Pose| RigSensor {
        id: id.into(),
        sensor: CalibratedSensor::new(model, PsdGeometry::default()),
        world_from_sensor: pose,
    };
    // Back to back: one looks along +z, the other along −z.
    let rig = Rig::new(vec![
        sensor("front", Pose::identity()),
        sensor(
            "back",
            Pose::new(
                Vector3::new(0.0, std::f64::consts::PI, 0.0),
                Vector3::new(500.0, 0.0, 0.0),
            ),
        ),
    ])
    .unwrap();
    assert!(rig.view_pairs().is_empty());
    let seen = [
        (0, Measurement::Point(Vector2::new(1.0, 0.5))),
        (1, Measurement::Point(Vector2::new(-1.0, 0.5))),
    ];
    let e = rig.locate(&seen, &LocateOptions::default()).unwrap_err();
    assert_eq!(e.status(), "no_shared_view", "{e}");
    assert!(e.to_string().contains("front, back"), "{e}");
    // One sensor twice, an unknown index, a single sensor.
    let e = rig
        .locate(&[seen[0], seen[0]], &LocateOptions::default())
        .unwrap_err();
    assert_eq!(e.status(), "invalid_input");
    let e = rig
        .locate(&[seen[0], (7, seen[1].1)], &LocateOptions::default())
        .unwrap_err();
    assert_eq!(e.status(), "unknown_sensor");
    let e = rig
        .locate(&seen[..1], &LocateOptions::default())
        .unwrap_err();
    assert_eq!(e.status(), "too_few_sensors");
    // Duplicate ids.
    let e = Rig::new(vec![
        sensor("a", Pose::identity()),
        sensor("a", Pose::identity()),
    ])
    .unwrap_err();
    assert!(e.to_string().contains("'a' appears twice"), "{e}");
}

#[test]
fn rig_covariance_splits_into_calibration_and_measurement() {
    let mut rig_sensors = support::three_sensor_rig(SensorModel::paper_lens2())
        .sensors()
        .to_vec();
    let cov = ParameterCovariance::from_params(
        &[Param::F, Param::Cx, Param::Cy],
        &DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![1e-4, 4e-6, 4e-6])),
    )
    .unwrap();
    for s in &mut rig_sensors {
        s.sensor.covariance = cov.clone();
    }
    let rig = Rig::new(rig_sensors).unwrap();
    let emitter = Vector3::new(50.0, 80.0, 100.0);
    let seen: Vec<(usize, Measurement)> = rig
        .sensors()
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let p = s.world_from_sensor.inverse().transform(&emitter);
            (k, Measurement::Point(support::measure(&s.sensor.model, &p)))
        })
        .collect();
    let options = LocateOptions {
        point_sigma_mm: 1e-3,
        ..LocateOptions::default()
    };
    let at = rig.locate(&seen, &options).unwrap();
    let sum = at.covariance_calibration + at.covariance_measurement;
    let total = at.triangulation.covariance;
    assert!((sum - total).abs().max() <= 1e-12 * total.abs().max());
    assert!(at.covariance_calibration[(0, 0)] > 0.0 && at.covariance_measurement[(0, 0)] > 0.0);
}

#[test]
fn invalid_covariances() {
    let two = |m: [[f64; 2]; 2]| DMatrix::from_fn(2, 2, |i, j| m[i][j]);
    let entries: Vec<String> = vec!["f".into(), "cx".into()];
    for (m, what) in [
        ([[1.0, 0.1], [0.2, 1.0]], "not symmetric"),
        ([[-1.0, 0.0], [0.0, 1.0]], "negative"),
        ([[f64::NAN, 0.0], [0.0, 1.0]], "non-finite"),
    ] {
        let e = ParameterCovariance::new(entries.clone(), two(m)).unwrap_err();
        assert!(e.to_string().contains(what), "{e}");
    }
    let e = ParameterCovariance::new(vec!["f".into(), "f".into()], DMatrix::identity(2, 2))
        .unwrap_err();
    assert!(e.to_string().contains("twice"), "{e}");
    let e =
        LocateError::from(ParameterCovariance::from_named(&["f"], &[vec![1.0, 2.0]]).unwrap_err());
    assert_eq!(e.status(), "invalid_covariance");
}

#[test]
fn maps_keep_unanswerable_cells_and_refuse_bad_options() {
    let errors = ParameterErrors::new(vec![(Param::F, 0.1)]).unwrap();
    let map = error_map(
        &folding_model(),
        &PsdGeometry::default(),
        &ErrorSource::Parameters(errors.clone()),
        &MapOptions {
            grid: 11,
            ..MapOptions::default()
        },
    )
    .unwrap();
    let failed: Vec<_> = map.cells.iter().filter(|c| c.values.is_err()).collect();
    assert!(!failed.is_empty() && failed.len() < map.cells.len());
    for cell in &failed {
        assert_eq!(
            cell.values.as_ref().unwrap_err().status(),
            "outside_valid_region"
        );
        assert!(cell.measured.norm() > 4.0);
    }
    for cell in map.cells.iter().filter_map(|c| c.values.as_ref().ok()) {
        assert!(cell
            .aoa_error
            .iter()
            .chain(cell.position_error.iter())
            .all(|v| v.is_finite()));
    }
    for options in [
        MapOptions {
            grid: 1,
            ..MapOptions::default()
        },
        MapOptions {
            distance_mm: 0.0,
            ..MapOptions::default()
        },
        MapOptions {
            distance_mm: f64::INFINITY,
            ..MapOptions::default()
        },
    ] {
        let e = error_map(
            &SensorModel::paper_lens1(),
            &PsdGeometry::default(),
            &ErrorSource::Parameters(errors.clone()),
            &options,
        )
        .unwrap_err();
        assert!(
            matches!(e.status(), "invalid_input" | "non_finite_input"),
            "{e}"
        );
    }
    let e = error_map(
        &SensorModel::paper_lens1(),
        &PsdGeometry::default(),
        &ErrorSource::Covariance {
            covariance: ParameterCovariance::none(),
            k: -2.0,
        },
        &MapOptions::default(),
    )
    .unwrap_err();
    assert_eq!(e.status(), "invalid_input");
    assert!(ParameterErrors::new(vec![(Param::F, 0.1), (Param::F, 0.2)]).is_err());
    assert!(ParameterErrors::new(vec![(Param::K1, f64::NAN)]).is_err());
}
