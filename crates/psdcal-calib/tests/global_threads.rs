//! The global search over `l1` runs its independent fits in parallel
//! (rayon); its answer must not depend on the number of threads: the same
//! bits with one thread and with four.

mod support;

use psdcal_calib::{calibrate, CalibrateOptions, RefineOptions};
use psdcal_model::{Param, SensorModel};

#[test]
fn the_l1_search_gives_the_same_bits_on_one_and_four_threads() {
    let mut truth = SensorModel::paper_lens2();
    truth.distortion.l1 = SensorModel::PAPER_L1;
    let s = support::scenario(truth, 9, 1e-3, 7);
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
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        pool.install(|| calibrate(&s.data, &options).expect("calibrates"))
    };
    let (one, four) = (on(1), on(4));
    let bits = |r: &psdcal_calib::CalibrationResult| -> Vec<u64> {
        r.model
            .values()
            .iter()
            .map(|v| v.to_bits())
            .chain([r.cost.to_bits()])
            .collect()
    };
    assert_eq!(bits(&one), bits(&four));
    let (g1, g4) = (
        one.global.expect("searched"),
        four.global.expect("searched"),
    );
    assert_eq!(g1.refinements, g4.refinements);
    assert_eq!(g1.minima.len(), g4.minima.len());
}
