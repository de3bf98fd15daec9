//! The diagnostics of a fit from surveyed 3-D points (docs/model.md §8.4,
//! "Diagnostics"): on data made here, independently of the fit — the true
//! model projects each emitter, the test's own pin-cushion formula turns the
//! impact point into unequal channel gains, and the survey's and the
//! channels' noise are drawn per seed — `gain_imbalance_suspected` fires on
//! unequal gains, `model_misfit` on a strong `k2` fitted with `k2` held at 0,
//! and twenty clean seeds raise nothing (the tests' level is p = 1e-6 per
//! fit), with the linearity check reliable.

use nalgebra::{Vector2, Vector3};
use psdcal_calib::{
    calibrate_surveyed, ImageObservations, Observation, SurveyedCalibration, SurveyedData,
    SurveyedOptions,
};
use psdcal_model::{DiagnosticCode, Model, Param, Pose, PsdGeometry, SensorModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// The channel noise of 40 dB as psdcal-sim's in-situ scene sets it, mm.
const SIGMA_M: f64 = 4e-4;

/// Relative gains `(x2, y1, y2)` of the imbalanced channels (x1 = 1).
const IMBALANCE: [f64; 3] = [1.03, 0.97, 1.02];

/// A scene: `n` emitters 1.5–5 m from the sensor, over the central 80 % of
/// the field of view of the first orientation; the others turned by a
/// quarter of the field of view about both axes.
fn scene(
    truth: &SensorModel,
    n: usize,
    orientations: usize,
    rng: &mut ChaCha8Rng,
) -> (Vec<Vector3<f64>>, Vec<Pose>) {
    let first = Pose::new(
        Vector3::new(
            rng.random_range(-0.3..0.3),
            rng.random_range(-0.3..0.3),
            rng.random_range(-3.0..3.0),
        ),
        Vector3::new(
            rng.random_range(-500.0..500.0),
            rng.random_range(-500.0..500.0),
            rng.random_range(-500.0..500.0),
        ),
    );
    let half = 0.4 * 9.0 / truth.intrinsics.f;
    let room_from_sensor = first.inverse();
    let points = psdcal_testkit::points_in_view(&room_from_sensor, half, n, rng);
    let turn = 0.25 * half;
    let poses = (0..orientations)
        .map(|k| {
            let s = [0.0, 1.0, -1.0][k % 3];
            Pose::new(Vector3::new(s * turn, -s * turn, 0.1 * s), Vector3::zeros()).compose(&first)
        })
        .collect();
    (points, poses)
}

/// The impact point a PSD with channel gains `(1, g_x2, g_y1, g_y2)` reports
/// for light at `m` (docs/model.md §1: bilinear shares of the current, the
/// pin-cushion formula on the amplified signals), written out here.
fn through_gains(m: &Vector2<f64>, g: [f64; 3]) -> Vector2<f64> {
    let (lx, ly) = (9.0, 9.0);
    let (u, v) = (2.0 * m.x / lx, 2.0 * m.y / ly);
    let x1 = 0.25 * (1.0 - u) * (1.0 - v);
    let x2 = 0.25 * (1.0 + u) * (1.0 + v) * g[0];
    let y1 = 0.25 * (1.0 + u) * (1.0 - v) * g[1];
    let y2 = 0.25 * (1.0 - u) * (1.0 + v) * g[2];
    let s = x1 + x2 + y1 + y2;
    Vector2::new(
        0.5 * lx * ((x2 + y1) - (x1 + y2)) / s,
        0.5 * ly * ((x2 + y2) - (x1 + y1)) / s,
    )
}

/// Measurements of every emitter by the true model, optionally through
/// unequal gains, with channel noise; the survey's positions with its noise.
fn data(
    truth: &SensorModel,
    gains: Option<[f64; 3]>,
    orientations: usize,
    survey_sigma: f64,
    seed: u64,
) -> SurveyedData {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (points, poses) = scene(truth, 24, orientations, &mut rng);
    let model = Model::standard(truth);
    let mut normal = |s: f64| s * rng.sample::<f64, _>(StandardNormal);
    let images = poses
        .iter()
        .enumerate()
        .map(|(i, pose)| ImageObservations {
            id: format!("{}", i + 1),
            points: points
                .iter()
                .enumerate()
                .map(|(led, p)| {
                    let m = model.project_point(pose, p).unwrap();
                    let m = gains.map_or(m, |g| through_gains(&m, g));
                    Observation {
                        led,
                        measured: m + Vector2::new(normal(SIGMA_M), normal(SIGMA_M)),
                    }
                })
                .collect(),
        })
        .collect();
    let surveyed = points
        .iter()
        .map(|p| {
            p + Vector3::new(
                normal(survey_sigma),
                normal(survey_sigma),
                normal(survey_sigma),
            )
        })
        .collect::<Vec<_>>();
    SurveyedData {
        names: (1..=surveyed.len()).map(|k| k.to_string()).collect(),
        points: surveyed,
        images,
        geometry: PsdGeometry::default(),
    }
}

fn fit(d: &SurveyedData, free: &[Param], survey_sigma: f64) -> SurveyedCalibration {
    let options = SurveyedOptions {
        free: free.to_vec(),
        survey_sigma_mm: survey_sigma,
        ..SurveyedOptions::default()
    };
    calibrate_surveyed(d, &options).unwrap()
}

const STANDARD: [Param; 5] = [Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2];

fn codes(c: &SurveyedCalibration) -> Vec<DiagnosticCode> {
    c.diagnostics.diagnostics.iter().map(|d| d.code).collect()
}

#[test]
fn unequal_gains_fitted_without_gains_are_suspected() {
    for (seed, orientations) in [(11u64, 1usize), (12, 3)] {
        let d = data(
            &SensorModel::paper_lens2(),
            Some(IMBALANCE),
            orientations,
            0.0,
            seed,
        );
        let c = fit(&d, &STANDARD, 0.0);

        assert!(
            c.diagnostics.has(DiagnosticCode::GainImbalanceSuspected),
            "seed {seed}: {:?}",
            c.diagnostics
        );
        let message = &c.diagnostics.diagnostics[0].message;
        assert!(message.contains("--gains"), "{message}");
        // The same scene with balanced channels raises nothing.
        let clean = fit(
            &data(&SensorModel::paper_lens2(), None, orientations, 0.0, seed),
            &STANDARD,
            0.0,
        );
        assert!(
            codes(&clean).is_empty(),
            "seed {seed}: {:?}",
            clean.diagnostics
        );
    }
}

#[test]
fn a_strong_k2_fitted_with_k2_held_at_zero_is_a_model_misfit() {
    let mut truth = SensorModel::paper_lens2();
    truth.distortion.k2 = 3e-4;
    for (seed, orientations) in [(21u64, 1usize), (22, 3)] {
        let d = data(&truth, None, orientations, 1.0, seed);
        let held = fit(&d, &[Param::F, Param::Cx, Param::Cy, Param::K1], 1.0);

        assert!(
            held.diagnostics.has(DiagnosticCode::ModelMisfit),
            "seed {seed}: {:?}",
            held.diagnostics
        );
        assert!(!held.diagnostics.has(DiagnosticCode::GainImbalanceSuspected));
        // Freeing k2 explains the data.
        let freed = fit(&d, &STANDARD, 1.0);
        assert!(
            codes(&freed).is_empty(),
            "seed {seed}: {:?}",
            freed.diagnostics
        );
    }
}

#[test]
fn twenty_clean_seeds_raise_nothing() {
    for seed in 0..20u64 {
        let orientations = 1 + (seed % 3) as usize;
        let survey = [0.0, 1.0, 3.0][(seed / 3 % 3) as usize];
        let d = data(
            &SensorModel::paper_lens2(),
            None,
            orientations,
            survey,
            100 + seed,
        );
        let c = fit(&d, &STANDARD, survey);

        assert!(codes(&c).is_empty(), "seed {seed}: {:?}", c.diagnostics);
        let t = c.diagnostics.cubic.expect("the cubic field is tested");
        assert!(t.df1 > 0 && t.f.is_finite(), "seed {seed}: {t:?}");
        assert!(
            c.linearity.verdict.is_reliable(),
            "seed {seed}: {:?}",
            c.linearity
        );
        assert_eq!(c.linearity.parameters.len(), STANDARD.len());
    }
}
