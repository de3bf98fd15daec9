//! Pose planning (docs/model.md §8.6), each part against something
//! independent: the per-pose information against the solver's normal
//! equations of the whole data set, the predicted covariance against the
//! spread of refinements on noise drawn from the stated point covariance,
//! the AoA metric against the angle between perturbed rays, the selection
//! against exhaustive search, and the refusals.

#[path = "support/planning.rs"]
mod planning;

use nalgebra::{DMatrix, DVector, Vector2};
use planning::some_poses;
use psdcal_calib::plan::{
    cell_centres, plan, plan_next, pose_information, predict, AoaMetric, Objective, PlanOptions,
    PlanSetup, PoseRanges, Scorer,
};
use psdcal_calib::{
    refine, CalibError, CalibrationData, CalibrationProblem, FitState, RefineOptions,
};
use psdcal_model::{CostKind, Model, Pose, PsdGeometry, SensorModel};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

fn setup(relative_noise: f64) -> PlanSetup {
    PlanSetup {
        model: Model::standard(&SensorModel::paper_lens2()),
        template: psdcal_model::paper_setup::scatter14(),
        geometry: PsdGeometry::default(),
        free: RefineOptions::default().free_names(),
        cost: CostKind::Template,
        relative_noise,
    }
}

#[test]
fn pose_information_sums_to_the_solvers_schur_complement() {
    let s = setup(1e-3);
    let poses = some_poses(&s, 6, 3);
    let points = poses
        .iter()
        .map(|p| psdcal_calib::plan::information::pose_points(&s, p).unwrap())
        .collect();
    let data = CalibrationData::from_points(&s.template, &[], points, s.geometry);
    let problem =
        CalibrationProblem::new(&data, CostKind::Template, &s.model, &s.free, None).unwrap();
    let state = FitState {
        model: s.model.clone(),
        poses: poses.clone(),
    };
    let ne = psdcal_calib::solver::solver::normal_equations(&problem, &state, None).unwrap();
    let expected = ne.schur_complement().unwrap();
    let mut sum = DMatrix::zeros(5, 5);
    for p in &poses {
        sum += pose_information(&s, p).unwrap().schur;
    }
    let scale = expected.norm();
    assert!(
        (&sum - &expected).norm() < 1e-9 * scale,
        "{sum} vs {expected}"
    );
}

#[test]
fn predicted_covariance_matches_the_spread_of_refinements() {
    // Noise drawn from each point's stated covariance, refined from the
    // truth; the sample variance of n estimates has relative std √(2/n).
    let s = setup(10f64.powf(-40.0 / 20.0) / 2f64.sqrt() * 0.12);
    let poses = some_poses(&s, 9, 5);
    let predicted = predict(&s, &poses, 5).unwrap();
    let clean: Vec<Vec<Vector2<f64>>> = poses
        .iter()
        .map(|p| psdcal_calib::plan::information::pose_points(&s, p).unwrap())
        .collect();
    let n = 200;
    let estimates: Vec<DVector<f64>> = (0..n)
        .map(|k| {
            let mut rng = ChaCha8Rng::seed_from_u64(100 + k);
            let noisy = clean
                .iter()
                .map(|image| {
                    image
                        .iter()
                        .map(|m| {
                            let c = psdcal_calib::plan::information::measured_covariance(&s, m);
                            let l = c.cholesky().unwrap().l();
                            let z = Vector2::new(
                                StandardNormal.sample(&mut rng),
                                StandardNormal.sample(&mut rng),
                            );
                            m + l * z
                        })
                        .collect()
                })
                .collect();
            let data = CalibrationData::from_points(&s.template, &[], noisy, s.geometry);
            let r = refine(&data, s.model.clone(), &poses, &RefineOptions::default()).unwrap();
            DVector::from_iterator(5, s.free.iter().map(|name| r.model.get(name).unwrap()))
        })
        .collect();
    planning::assert_variances_match(&estimates, &s.free, predicted.covariance.matrix());
}

#[test]
fn aoa_metric_is_the_squared_angle_between_perturbed_rays() {
    let s = setup(1e-3);
    let metric = AoaMetric::new(&s.model, &s.free, cell_centres(&s.geometry, 5)).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let scale = [1e-4, 1e-4, 1e-4, 1e-6, 1e-8];
    for _ in 0..5 {
        let delta: Vec<f64> = scale
            .iter()
            .map(|s| {
                let z: f64 = StandardNormal.sample(&mut rng);
                s * z
            })
            .collect();
        let mut moved = s.model.clone();
        for (name, d) in s.free.iter().zip(&delta) {
            moved.set(name, s.model.get(name).unwrap() + d).unwrap();
        }
        let dv = DVector::from_column_slice(&delta);
        for (m, h) in metric.points.iter().zip(&metric.weights) {
            let ray = |model: &Model| {
                let ab = model.ray(m);
                nalgebra::Vector3::new(ab.x, ab.y, 1.0).normalize()
            };
            let (a, b) = (ray(&s.model), ray(&moved));
            let angle = a.cross(&b).norm().atan2(a.dot(&b));
            let predicted = (dv.transpose() * h * &dv)[(0, 0)];
            assert!(
                (angle * angle - predicted).abs() < 1e-3 * predicted + 1e-20,
                "angle² {} vs {predicted}",
                angle * angle
            );
        }
    }
}

#[test]
fn selection_is_near_the_exhaustive_optimum_and_deterministic() {
    let s = setup(1e-3);
    let poses = some_poses(&s, 14, 21);
    let infos: Vec<_> = poses
        .iter()
        .map(|p| pose_information(&s, p).unwrap())
        .collect();
    let metric = AoaMetric::new(&s.model, &s.free, cell_centres(&s.geometry, 5)).unwrap();
    for objective in [Objective::Rms, Objective::Max] {
        let scorer = Scorer::new(&infos, &metric, objective, None);
        let chosen = scorer.select(3);
        assert_eq!(chosen, scorer.select(3));
        let score = |set: &[usize]| {
            let (s, m) = scorer.sums(set);
            scorer.score(&s, &m, false)
        };
        let mut best = f64::INFINITY;
        for a in 0..14 {
            for b in a + 1..14 {
                for c in b + 1..14 {
                    best = best.min(score(&[a, b, c]));
                }
            }
        }
        // Exchange is a local search: within 10 % of the best variance.
        assert!(
            score(&chosen) <= 1.1 * best,
            "{objective:?}: {} vs {best}",
            score(&chosen)
        );
    }
}

#[test]
fn plan_keeps_every_led_inside_and_next_lowers_the_sigma() {
    let s = setup(1e-3);
    let options = PlanOptions {
        images: 5,
        candidates: 300,
        ..PlanOptions::default()
    };
    let p = plan(&s, &options).unwrap();
    assert_eq!(p.poses.len(), 5);
    let h = 0.5 * s.geometry.lx - options.ranges.margin_mm;
    for c in &p.poses {
        assert!(c.tilt <= options.ranges.tilt_max);
        for xy in &s.template {
            let m = s.model.project(&c.pose, xy).unwrap();
            assert!(m.x.abs() <= h && m.y.abs() <= h);
        }
    }
    assert_eq!(p, plan(&s, &options).unwrap());
    let taken: Vec<Pose> = p.poses.iter().map(|c| c.pose).collect();
    let next = plan_next(&s, &options, &taken).unwrap();
    let (before, _) = next.before.unwrap();
    assert!((before - p.prediction.rms).abs() < 1e-9 * before);
    assert!(next.prediction.rms < before);
    // The prediction with the next pose is that of all six poses together.
    let mut all = taken.clone();
    all.push(next.poses[0].pose);
    let joint = predict(&s, &all, options.grid).unwrap().rms;
    assert!((next.prediction.rms - joint).abs() < 1e-9 * joint);
}

#[test]
fn bad_ranges_are_refused_with_what_to_change() {
    let s = setup(1e-3);
    let message = |options: PlanOptions| match plan(&s, &options) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("accepted"),
    };
    let too_close = message(PlanOptions {
        ranges: PoseRanges {
            distance_mm: Some((10.0, 20.0)),
            ..PoseRanges::default()
        },
        ..PlanOptions::default()
    });
    assert!(too_close.contains("allow distances up to"), "{too_close}");
    let tilt = message(PlanOptions {
        ranges: PoseRanges {
            tilt_max: 95f64.to_radians(),
            ..PoseRanges::default()
        },
        ..PlanOptions::default()
    });
    assert!(tilt.contains("--tilt-max"), "{tilt}");
    let few = plan(
        &s,
        &PlanOptions {
            images: 2,
            ..PlanOptions::default()
        },
    );
    assert!(matches!(few, Err(CalibError::TooFewImages { .. })));
    // Just inside the default range's lower end: the template fits nowhere.
    let centre = s.template.iter().sum::<Vector2<f64>>() / s.template.len() as f64;
    let radius = s
        .template
        .iter()
        .map(|p| (p - centre).norm())
        .fold(0.0, f64::max);
    let s0 = s.model.get("f").unwrap() * radius / (4.5 - 0.2);
    let narrow = message(PlanOptions {
        ranges: PoseRanges {
            distance_mm: Some((0.55 * s0, 0.6 * s0)),
            ..PoseRanges::default()
        },
        ..PlanOptions::default()
    });
    assert!(narrow.contains("margin"), "{narrow}");
}
