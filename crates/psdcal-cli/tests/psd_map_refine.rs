//! `calibrate --psd-map … --refine-psd-map` (docs/model.md §8.3): a map
//! deliberately biased by a sparse, noisy scan (1 mm raster, stage σ 3 µm,
//! 30 dB) is refined by the calibration data with the scan as its prior.
//! Pooled over 8 seeds, the refined map is closer to the true field and the
//! angles are better than with the map held fixed; every coefficient's σ
//! after refinement is at most the scan's (the record's `matrix` against
//! the scan's `σ² U`).
//! (A facade test that lives here because it needs the `testing` feature,
//! which this crate's tests turn on.)

use psdcal::{refine_seed, RefineErrors, ScanSpec};

#[test]
fn refining_a_biased_map_improves_the_map_and_the_angles() {
    let scan = ScanSpec {
        step_mm: 1.0,
        stage_sigma_um: 3.0,
        snr_db: 30.0,
    };
    let seeds: Vec<RefineErrors> = (1..=8).map(|s| refine_seed(s, &scan).unwrap()).collect();
    let rms = |f: fn(&RefineErrors) -> f64| {
        (seeds.iter().map(|e| f(e).powi(2)).sum::<f64>() / seeds.len() as f64).sqrt()
    };
    let (map_held, map_refined) = (
        rms(|e| e.held_map_error_mm),
        rms(|e| e.refined_map_error_mm),
    );
    let (held, refined) = (rms(|e| e.held), rms(|e| e.refined));
    eprintln!("{seeds:#?}");
    eprintln!(
        "map error vs truth: held {:.3} µm, refined {:.3} µm; angles: held {:.1} µrad, refined {:.1} µrad",
        1e3 * map_held,
        1e3 * map_refined,
        1e6 * held,
        1e6 * refined
    );
    assert!(map_refined < map_held, "{map_refined:e} vs {map_held:e}");
    assert!(refined < held, "{refined:e} vs {held:e}");
    for e in &seeds {
        assert!(
            e.refined_max_sigma_mm <= e.held_max_sigma_mm * (1.0 + 1e-9),
            "{e:?}"
        );
    }
}
