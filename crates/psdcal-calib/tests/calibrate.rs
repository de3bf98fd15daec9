//! The whole calibration from automatic initialisation (no focal guess).

mod support;

use psdcal_calib::{calibrate, CalibError, CalibrateOptions, RefineOptions};
use psdcal_model::{Param, SensorModel};
use support::{assert_recovered, scenario};

#[test]
fn noise_free_end_to_end_both_lenses() {
    for (name, truth) in [
        ("lens1", SensorModel::paper_lens1()),
        ("lens2", SensorModel::paper_lens2()),
    ] {
        for seed in [1, 2] {
            let s = scenario(truth, 9, 0.0, seed);
            let r = calibrate(&s.data, &CalibrateOptions::default()).unwrap();
            assert!(
                r.statistics.residual_mm2 < 1e-12,
                "{name}: residual {:e}",
                r.statistics.residual_mm2
            );
            assert_recovered(name, &r.sensor_model(), &truth, &r.free);
        }
    }
}

#[test]
fn noise_free_end_to_end_with_every_lens_term_freed() {
    for base in [SensorModel::paper_lens1(), SensorModel::paper_lens2()] {
        let mut truth = base;
        truth.intrinsics.skew = 0.01;
        truth.distortion.k3 = 1e-7;
        truth.distortion.p1 = 2e-4;
        truth.distortion.p2 = -3e-4;
        let s = scenario(truth, 9, 0.0, 8);
        let options = CalibrateOptions {
            refine: RefineOptions {
                free: vec![
                    Param::F,
                    Param::Cx,
                    Param::Cy,
                    Param::Skew,
                    Param::K1,
                    Param::K2,
                    Param::K3,
                    Param::P1,
                    Param::P2,
                ],
                ..RefineOptions::default()
            },
            ..CalibrateOptions::default()
        };
        let r = calibrate(&s.data, &options).unwrap();
        assert!(
            r.statistics.residual_mm2 < 1e-12,
            "residual {:e}",
            r.statistics.residual_mm2
        );
        assert_recovered("all lens terms", &r.sensor_model(), &truth, &r.free);
    }
}

#[test]
fn noise_free_end_to_end_with_l1_freed() {
    for (name, base) in [
        ("lens1", SensorModel::paper_lens1()),
        ("lens2", SensorModel::paper_lens2()),
    ] {
        let mut truth = base;
        truth.distortion.l1 = SensorModel::PAPER_L1;
        let s = scenario(truth, 9, 0.0, 3);
        let options = CalibrateOptions {
            refine: RefineOptions {
                free: vec![
                    Param::F,
                    Param::Cx,
                    Param::Cy,
                    Param::K1,
                    Param::K2,
                    Param::L1,
                ],
                ..RefineOptions::default()
            },
            ..CalibrateOptions::default()
        };
        let r = calibrate(&s.data, &options).unwrap();
        assert!(
            r.statistics.residual_mm2 < 1e-12,
            "{name}: residual {:e}",
            r.statistics.residual_mm2
        );
        assert_recovered(name, &r.sensor_model(), &truth, &r.free);
        let g = r.global.as_ref().expect("global search ran");
        assert!(g.minima[0].cost < 1e-12);
    }
}

#[test]
fn degenerate_input_is_refused_with_its_cause() {
    let truth = SensorModel::paper_lens2();
    let mut s = scenario(truth, 9, 0.0, 1);
    s.data.images.truncate(2);
    match calibrate(&s.data, &CalibrateOptions::default()) {
        Err(CalibError::TooFewImages { usable: 2, .. }) => {}
        other => panic!("expected TooFewImages, got {other:?}"),
    }
}
