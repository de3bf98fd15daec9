//! `diff_calibrations` against closed forms (docs/model.md §8.8): two
//! pinholes whose optical centres differ by δ, each with σ(cx) only.

use nalgebra::DMatrix;
use psdcal_locate::{diff_calibrations, CalibratedSensor, ParameterCovariance};
use psdcal_model::{Param, PsdGeometry, SensorModel};

fn pinhole(cx: f64, sigma_cx: f64) -> CalibratedSensor {
    let cov = ParameterCovariance::from_params(
        &[Param::Cx],
        &DMatrix::from_element(1, 1, sigma_cx * sigma_cx),
    )
    .unwrap();
    CalibratedSensor::new(SensorModel::pinhole(8.0, cx, 0.0), PsdGeometry::default())
        .with_covariance(cov)
}

#[test]
fn shifted_centres_give_the_closed_form() {
    let (delta, sa, sb) = (0.01, 0.003, 0.004);
    let (a, b) = (pinhole(0.0, sa), pinhole(delta, sb));
    let diff = diff_calibrations(&a, &b, 21).unwrap();
    assert_eq!(diff.answered, 21 * 21);
    let mut max: f64 = 0.0;
    for p in &diff.points {
        let v = p.values.as_ref().unwrap();
        let x = p.measured.x;
        // αx = atan((x − cx)/f); ∂αx/∂cx = −cos²αx / f.
        let expected = ((x - delta) / 8.0).atan() - (x / 8.0).atan();
        assert!((v.delta().x - expected).abs() < 1e-15 && v.delta().y.abs() < 1e-15);
        let ga = (x / 8.0).atan().cos().powi(2) / 8.0;
        let gb = ((x - delta) / 8.0).atan().cos().powi(2) / 8.0;
        let sigma = ((ga * sa).powi(2) + (gb * sb).powi(2)).sqrt();
        assert!((v.sigma_along() / sigma - 1.0).abs() < 1e-12);
        assert!((v.z().unwrap() - expected.abs() / sigma).abs() < 1e-9);
        max = max.max(expected.abs());
    }
    assert!((diff.max_delta.0 - max).abs() < 1e-15);
    // A shifted centre moves the angles most at the centre (cos²α/f).
    assert!(diff.max_delta.1.x.abs() < 0.5, "{:?}", diff.max_delta);
}

#[test]
fn a_calibration_against_itself_and_other_areas() {
    let a = pinhole(0.2, 0.003);
    let diff = diff_calibrations(&a, &a, 11).unwrap();
    assert_eq!(diff.max_delta.0, 0.0);
    assert_eq!(diff.max_z.unwrap().0, 0.0);
    let other = CalibratedSensor::new(
        SensorModel::pinhole(8.0, 0.0, 0.0),
        PsdGeometry { lx: 10.0, ly: 10.0 },
    );
    assert!(diff_calibrations(&a, &other, 11).is_err());
    assert!(diff_calibrations(&a, &a, 1).is_err());
}
