//! The misplaced-LED check (`psdcal_calib::misplaced`): one LED's template
//! coordinates mistyped are found, by index, in simulated data of both
//! lenses with noise; correct templates raise nothing; and a calibration
//! that fails because of the typo says which LED, not "poses parallel".

mod support;

use psdcal_calib::misplaced::misplaced_led;
use psdcal_calib::{calibrate, CalibError, CalibrateOptions};
use psdcal_model::SensorModel;

/// σ of the measured points, mm: about what 40 dB gives (docs/model.md §1.3).
const SIGMA_MM: f64 = 1e-3;

fn lenses() -> [SensorModel; 2] {
    [SensorModel::paper_lens1(), SensorModel::paper_lens2()]
}

#[test]
fn correct_templates_blame_no_led() {
    for truth in lenses() {
        for seed in 1..=10 {
            let s = support::scenario(truth, 12, SIGMA_MM, seed);
            assert_eq!(
                misplaced_led(&s.data),
                None,
                "seed {seed}, f = {}",
                truth.intrinsics.f
            );
        }
    }
}

#[test]
fn one_mistyped_led_is_found() {
    for truth in lenses() {
        for seed in 1..=6u64 {
            let s = support::scenario(truth, 12, SIGMA_MM, seed);
            let led = (seed as usize * 5) % s.data.template.len();
            // A dropped or doubled digit, a wrong sign, a swapped coordinate.
            let x = s.data.template[led].x;
            let y = s.data.template[led].y;
            let typos = [(x * 10.0, y), (x, y / 10.0), (-x, y), (y, x), (x + 30.0, y)];
            for typo in typos {
                if (typo.0 - x).hypot(typo.1 - y) < 20.0 {
                    continue; // not a typo this LED can show (x ≈ y or x ≈ 0)
                }
                let mut data = s.data.clone();
                data.template[led] = nalgebra::Vector2::new(typo.0, typo.1);
                let found = misplaced_led(&data)
                    .unwrap_or_else(|| panic!("seed {seed}: LED {led} at {typo:?} not found"));
                assert_eq!(found.led, led, "seed {seed}, typo {typo:?}: {found:?}");
            }
        }
    }
}

#[test]
fn a_failed_calibration_names_the_mistyped_led() {
    let truth = SensorModel::paper_lens2();
    let s = support::scenario(truth, 12, SIGMA_MM, 3);
    let mut data = s.data.clone();
    data.template[0].x *= 10.0;
    let options = CalibrateOptions::default();
    match calibrate(&data, &options) {
        Err(CalibError::MisplacedLed { led, score, .. }) => {
            assert_eq!(led, 0);
            assert!(score > 10.0, "score {score}");
        }
        other => panic!("expected MisplacedLed, got {other:?}"),
    }
    // Without the typo the same data calibrate.
    calibrate(&s.data, &options).expect("the correct template calibrates");
}
