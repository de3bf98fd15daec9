//! Scenarios and the simulator: poses on the sensor and covering it, the
//! gain imbalance's spread (P43), the noise-free simulation against the model.

use psdcal_model::psd::{impact_point, transimpedance_gain};
use psdcal_model::{Model, PsdGeometry};
use psdcal_sim::scenario::{
    draw_imbalance, draw_poses, IMBALANCE_FREQUENCY_HZ, NOMINAL_C_FARAD, NOMINAL_R_OHM,
};
use psdcal_sim::{simulate, Lens, SimulationOptions, TemplateKind};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn poses_keep_every_led_on_the_sensor_and_cover_it() {
    let geometry = PsdGeometry::default();
    for lens in [Lens::One, Lens::Two] {
        for kind in [TemplateKind::Scatter14, TemplateKind::Grid] {
            let truth = lens.model();
            let template = kind.template();
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            let poses = draw_poses(&truth, &geometry, &template, 9, &mut rng).unwrap();
            let model = Model::standard(&truth);
            let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
            for p in &poses {
                let z = p.t.z / truth.intrinsics.f;
                assert!((70.0..150.0).contains(&z), "distance {} f", z);
                let tilt = p.rotation()[(2, 2)].acos().to_degrees();
                assert!(tilt <= 30.0 + 1e-9, "tilt {tilt}°");
                for xy in &template.leds {
                    let m = model.project_to_tolerance(p, xy).unwrap();
                    assert!(m.x.abs() <= 4.4 && m.y.abs() <= 4.4);
                    for k in 0..2 {
                        lo[k] = lo[k].min(m[k]);
                        hi[k] = hi[k].max(m[k]);
                    }
                }
            }
            // The images together span most of the 9 mm in both directions.
            for k in 0..2 {
                assert!(
                    hi[k] - lo[k] > 6.5,
                    "{lens:?} {kind:?}: axis {k} spans {:.2} mm",
                    hi[k] - lo[k]
                );
            }
        }
    }
}

#[test]
fn gain_imbalance_has_the_spread_of_the_component_tolerances() {
    // The paper's nominal gain at 13.793 kHz.
    let k0 = transimpedance_gain(NOMINAL_R_OHM, NOMINAL_C_FARAD, IMBALANCE_FREQUENCY_HZ);
    assert!((k0 - 53_572.0).abs() < 1.0, "K = {k0}");
    // ln K = ln R − ln(1 + x), x = 2π f R C: d ln K = (1/(1+x)) dR/R − (x/(1+x)) dC/C with
    // uniform dR/R ∈ ±1 %, dC/C ∈ ±15 % (variance a²/3). ln g = ln K_k − ln K_x1 doubles it.
    let x = 2.0 * std::f64::consts::PI * IMBALANCE_FREQUENCY_HZ * NOMINAL_R_OHM * NOMINAL_C_FARAD;
    let var_ln_k = (0.01 / (1.0 + x)).powi(2) / 3.0 + (0.15 * x / (1.0 + x)).powi(2) / 3.0;
    let predicted = (2.0 * var_ln_k).sqrt();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let n = 4000;
    let logs: Vec<f64> = (0..n).map(|_| draw_imbalance(&mut rng).x2.ln()).collect();
    let mean = logs.iter().sum::<f64>() / n as f64;
    let std = (logs.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
    // The sample std of 4000 draws scatters by about 1/sqrt(2·4000) ≈ 1.1 %; allow 5 %.
    assert!(
        (std / predicted - 1.0).abs() < 0.05,
        "std of ln g {std:.4} vs {predicted:.4}"
    );
    assert!(
        mean.abs() < 4.0 * predicted / (n as f64).sqrt(),
        "biased: {mean}"
    );
}

#[test]
fn noise_free_simulation_is_the_model() {
    let options = SimulationOptions {
        snr_db: None,
        psd_distortion: true,
        ..SimulationOptions::default()
    };
    let sim = simulate(&options, &mut ChaCha8Rng::seed_from_u64(5)).unwrap();
    assert_eq!(sim.images.len(), 9);
    let truth = Model::standard(&sim.truth);
    for (im, pose) in sim.images.iter().zip(&sim.poses) {
        for p in &im.points {
            let expected = truth
                .project_to_tolerance(pose, &sim.template.leds[p.led])
                .unwrap();
            assert!((p.measured - expected).norm() < 1e-12);
            assert!(
                (impact_point(&options.geometry, &p.amplitudes).unwrap() - expected).norm() < 1e-12
            );
        }
    }
    // With imbalance the measured points are biased by the gains, as docs/model.md §1 says.
    let options = SimulationOptions {
        snr_db: None,
        imbalance: true,
        ..SimulationOptions::default()
    };
    let sim = simulate(&options, &mut ChaCha8Rng::seed_from_u64(5)).unwrap();
    let p = &sim.images[0].points[0];
    let corrected =
        psdcal_model::psd::impact_point_with_gains(&options.geometry, &p.amplitudes, &sim.gains)
            .unwrap();
    assert!((corrected - p.true_measured).norm() < 1e-12);
    assert!(
        (p.measured - p.true_measured).norm() > 1e-3,
        "the imbalance biases the point"
    );
}

#[test]
fn fewer_than_three_images_are_refused() {
    let options = SimulationOptions {
        images: 2,
        ..SimulationOptions::default()
    };
    assert!(simulate(&options, &mut ChaCha8Rng::seed_from_u64(1)).is_err());
}
