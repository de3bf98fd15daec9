//! Time of the whole fit from surveyed 3-D points (`calibrate_surveyed`:
//! checks, DLT starts, competing refinements, covariance with the survey
//! noise, diagnostics and linearity check), lens 2 at 40 dB (σ 0.4 µm):
//!
//! - a 3-D template of 20 LEDs (a 300 × 300 × 200 mm box) 0.8–1 m away,
//!   in 1 and in 3 images (tilted up to 20°), exact survey;
//! - in situ: 20 emitters 1.5–5 m away in a room, 3 sensor orientations
//!   (turned by a quarter of the field of view), survey σ 2 mm.

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{Vector2, Vector3};
use psdcal_calib::{
    calibrate_surveyed, ImageObservations, Observation, SurveyedData, SurveyedOptions,
};
use psdcal_model::{Model, Pose, PsdGeometry, SensorModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

const SIGMA_M: f64 = 4e-4;

fn observe(points: &[Vector3<f64>], poses: &[Pose], rng: &mut ChaCha8Rng) -> SurveyedData {
    let model = Model::standard(&SensorModel::paper_lens2());
    let images = poses
        .iter()
        .enumerate()
        .map(|(i, pose)| ImageObservations {
            id: format!("{}", i + 1),
            points: points
                .iter()
                .enumerate()
                .map(|(led, p)| {
                    let e = Vector2::new(rng.sample(StandardNormal), rng.sample(StandardNormal));
                    Observation {
                        led,
                        measured: model.project_point(pose, p).expect("in view") + SIGMA_M * e,
                    }
                })
                .collect(),
        })
        .collect();
    SurveyedData {
        names: (1..=points.len()).map(|k| k.to_string()).collect(),
        points: points.to_vec(),
        images,
        geometry: PsdGeometry::default(),
    }
}

/// The 3-D template seen in `images` poses.
fn template(images: usize, seed: u64) -> SurveyedData {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let points: Vec<Vector3<f64>> = (0..20)
        .map(|_| {
            Vector3::new(
                rng.random_range(-150.0..150.0),
                rng.random_range(-150.0..150.0),
                rng.random_range(0.0..200.0),
            )
        })
        .collect();
    let poses: Vec<Pose> = (0..images)
        .map(|k| {
            let tilt = 0.35 * k as f64 / images.max(2) as f64;
            Pose::new(
                Vector3::new(tilt, -0.5 * tilt, 0.2 * k as f64),
                Vector3::new(0.0, 0.0, rng.random_range(800.0..1000.0)),
            )
        })
        .collect();
    observe(&points, &poses, &mut rng)
}

/// 20 emitters in a room, 3 orientations; the survey with σ 2 mm.
fn room(seed: u64) -> SurveyedData {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let first = Pose::new(
        Vector3::new(0.2, -0.1, 1.0),
        Vector3::new(300.0, -200.0, 400.0),
    );
    let half = 0.4 * 9.0 / 8.0;
    let room_from_sensor = first.inverse();
    let points: Vec<Vector3<f64>> =
        psdcal_testkit::points_in_view(&room_from_sensor, half, 20, &mut rng);
    let turn = 0.25 * half;
    let poses: Vec<Pose> = [0.0, 1.0, -1.0]
        .iter()
        .map(|s| {
            Pose::new(Vector3::new(s * turn, -s * turn, 0.1 * s), Vector3::zeros()).compose(&first)
        })
        .collect();
    let mut data = observe(&points, &poses, &mut rng);
    for p in &mut data.points {
        *p += 2.0 * Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal));
    }
    data
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("surveyed");
    group.sample_size(20);
    for images in [1usize, 3] {
        let data = template(images, 7);
        let options = SurveyedOptions::default();
        calibrate_surveyed(&data, &options).expect("the bench's template fits");
        group.bench_function(format!("template_20_points_{images}_images"), |b| {
            b.iter(|| calibrate_surveyed(&data, &options).unwrap())
        });
    }
    let data = room(7);
    let options = SurveyedOptions {
        survey_sigma_mm: 2.0,
        ..SurveyedOptions::default()
    };
    calibrate_surveyed(&data, &options).expect("the bench's room fits");
    group.bench_function("in_situ_20_emitters_3_orientations", |b| {
        b.iter(|| calibrate_surveyed(&data, &options).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
