//! The raw recording simulator (docs/model.md §8.5): record layout, each
//! impairment switched on alone, the ADC's quantisation, refusals.

use psdcal_sim::raw::{Frame, Impairment, Impairments, RawPlan, RawRecord, QUANTUM_V};
use psdcal_sim::SimError;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn plan(impairments: Impairments, snr_db: Option<f64>) -> RawPlan {
    RawPlan {
        sample_rate_hz: 20_000.0,
        record_samples: 400,
        records: vec![
            RawRecord {
                leds: vec![(1000.0, [1.0, 0.5, 0.25, 0.0])],
            },
            RawRecord {
                leds: vec![(900.0, [0.2; 4]), (1100.0, [0.3; 4])],
            },
        ],
        snr_db,
        impairments,
    }
}

fn generate(plan: &RawPlan, seed: u64) -> Result<Vec<Frame>, SimError> {
    let mut out = Vec::new();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    plan.generate(&mut rng, |frames: &[Frame]| -> Result<(), SimError> {
        out.extend_from_slice(frames);
        Ok(())
    })?;
    Ok(out)
}

#[test]
fn records_back_to_back_with_their_tones() {
    let clean = generate(&plan(Impairments::none(), None), 1).unwrap();
    assert_eq!(clean.len(), 800);
    // A channel without light is exactly zero; the others peak at their
    // amplitude (20 samples a cycle: the peak is within sin(π/20) of it).
    assert!(clean[..400].iter().all(|f| f[3] == 0.0));
    let peak = clean[..400].iter().map(|f| f[0].abs()).fold(0.0, f64::max);
    assert!(
        peak <= 1.0 && peak > (std::f64::consts::PI / 20.0).cos(),
        "{peak}"
    );
    // Deterministic per seed.
    assert_eq!(
        clean,
        generate(&plan(Impairments::none(), None), 1).unwrap()
    );
}

#[test]
fn each_impairment_alone() {
    let clean = generate(&plan(Impairments::none(), None), 2).unwrap();
    let dc = generate(&plan(Impairments::only(&[Impairment::Dc]), None), 2).unwrap();
    let offsets = Impairments::default().dc_offset_v;
    for (a, b) in clean.iter().zip(&dc) {
        for k in 0..4 {
            assert!((b[k] - a[k] - offsets[k]).abs() < 1e-12);
        }
    }
    let q = generate(
        &plan(Impairments::only(&[Impairment::Quantise]), Some(30.0)),
        2,
    )
    .unwrap();
    for f in &q {
        for v in f {
            let steps = v / QUANTUM_V;
            assert!((steps - steps.round()).abs() < 1e-9, "{v}");
        }
    }
    // Hum, drift, transients and the clock change the samples; none adds a
    // DC offset by itself.
    for item in [
        Impairment::Hum,
        Impairment::Drift,
        Impairment::Transients,
        Impairment::Clock,
    ] {
        let x = generate(&plan(Impairments::only(&[item]), None), 2).unwrap();
        assert!(
            x.iter()
                .zip(&clean)
                .any(|(a, b)| (a[0] - b[0]).abs() > 1e-6),
            "{item:?}"
        );
    }
}

#[test]
fn bad_plans_are_refused() {
    let mut p = plan(Impairments::default(), Some(40.0));
    p.sample_rate_hz = f64::NAN;
    assert!(matches!(generate(&p, 1), Err(SimError::Options(_))));
    let mut p = plan(Impairments::default(), Some(40.0));
    p.records[0].leds[0].0 = 15_000.0;
    assert!(matches!(generate(&p, 1), Err(SimError::Options(_))));
    let mut p = plan(Impairments::default(), Some(f64::INFINITY));
    p.record_samples = 10;
    assert!(matches!(generate(&p, 1), Err(SimError::Options(_))));
}
