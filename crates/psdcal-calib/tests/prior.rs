//! A PSD map refined with its scan as a prior (docs/model.md §8.3,
//! `psdcal_calib::prior`, `CalibrateOptions::prior`): the prior residuals'
//! Jacobian against central differences and their cost against
//! `s² (m − μ)ᵀ Σ⁻¹ (m − μ)` with an independent inverse; a very tight prior
//! gives the fixed map's answer (within 5 σ of what the prior lets the map
//! move, carried through `G = ∂θ̂/∂m`); a biased map comes closer to the
//! truth when refined, and its coefficients' σ shrink.

mod support;

use nalgebra::{DMatrix, DVector, Vector2};
use psdcal_calib::{
    calibrate, carry_fixed_covariance, CalibrateOptions, CalibrationData, CalibrationProblem,
    CostKind, FitState, Prior, Problem,
};
use psdcal_model::stages::{MapBasis, MapFrame, PsdMap};
use psdcal_model::{Model, ParameterCovariance, Pose, SensorModel, Stage};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Lens 2 after a polynomial map of order 2 (12 coefficients, its second
/// example field: tens of µm).
fn truth() -> (Model, PsdMap) {
    let map = PsdMap::new(
        MapBasis::Polynomial { order: 2 },
        MapFrame::centred(9.0, 9.0),
        None,
    )
    .unwrap();
    let mut model = Model::standard(&SensorModel::paper_lens2())
        .with_stage(0, Box::new(map.clone()))
        .unwrap();
    for (p, v) in map.parameters().iter().zip(&map.example_parameters()[1]) {
        model.set(&p.name, *v).unwrap();
    }
    (model, map)
}

fn names(map: &PsdMap) -> Vec<String> {
    map.parameters().iter().map(|p| p.name.clone()).collect()
}

/// 12 images of the 14-LED template, point noise `sigma` mm.
fn scene(model: &Model, seed: u64, sigma: f64) -> (CalibrationData, Vec<Pose>) {
    let template = support::template(14);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let poses = support::poses_for(&SensorModel::paper_lens2(), &template, 12, &mut rng);
    let mut points: Vec<Vec<Vector2<f64>>> = poses
        .iter()
        .map(|pose| {
            template
                .iter()
                .map(|xy| model.project(pose, xy).unwrap())
                .collect()
        })
        .collect();
    psdcal_testkit::add_noise(&mut points, &Normal::new(0.0, sigma).unwrap(), &mut rng);
    (support::calibration_data(&template, &[], points), poses)
}

/// A scan's covariance: `σ_map²` on the diagonal, correlated neighbours.
fn scan_covariance(names: &[String], sigma_map: f64) -> ParameterCovariance {
    let n = names.len();
    let c = DMatrix::from_fn(n, n, |i, j| {
        sigma_map.powi(2) * 0.5f64.powi((i as i32 - j as i32).abs())
    });
    ParameterCovariance::new(names.to_vec(), c).unwrap()
}

/// The prior rows a problem visits (one-row terms without a pose block):
/// residuals and, with `jacobians`, their `∂r/∂θ_free` rows.
fn prior_rows(
    problem: &CalibrationProblem<'_>,
    state: &FitState,
    jacobians: bool,
) -> Vec<(f64, Vec<f64>)> {
    let mut rows = Vec::new();
    problem
        .evaluate(state, jacobians, &mut |t| {
            if t.r.len() == 1 && t.block.is_none() {
                rows.push((t.r[0], t.a.to_vec()));
            }
        })
        .unwrap();
    rows
}

#[test]
fn prior_residuals_have_their_jacobian_and_cost() {
    let (model, map) = truth();
    let (data, poses) = scene(&model, 3, 1e-3);
    let names = names(&map);
    let cov = scan_covariance(&names, 2e-3);
    let mean: Vec<f64> = names.iter().map(|n| model.get(n).unwrap() + 1e-3).collect();
    let prior = Prior::new(&cov, &mean, 0.7).unwrap();
    let mut free = vec!["f".to_string(), "k1".to_string()];
    free.extend(names.iter().cloned());
    let problem = CalibrationProblem::new(&data, CostKind::Template, &model, &free, None)
        .unwrap()
        .with_prior(&model, Some(&prior))
        .unwrap();
    let state = FitState {
        model: model.clone(),
        poses: poses.clone(),
    };
    let rows = prior_rows(&problem, &state, true);
    assert_eq!(rows.len(), names.len());
    // Cost: s² (m − μ)ᵀ Σ⁻¹ (m − μ), Σ⁻¹ by LU (not the Cholesky behind L).
    let d = DVector::from_iterator(
        names.len(),
        names
            .iter()
            .zip(&mean)
            .map(|(n, mu)| model.get(n).unwrap() - mu),
    );
    let inv = cov.matrix().clone().lu().try_inverse().unwrap();
    let expected = 0.49 * (d.transpose() * inv * &d)[(0, 0)];
    let cost: f64 = rows.iter().map(|(r, _)| r * r).sum();
    assert!(
        (cost - expected).abs() <= 1e-9 * expected,
        "{cost} {expected}"
    );
    // ∂r/∂θ by central differences, every freed column; f and k1 do not
    // enter the prior.
    let h = 1e-5;
    for (slot, name) in free.iter().enumerate() {
        let at = |delta: f64| {
            let mut m = model.clone();
            m.set(name, model.get(name).unwrap() + delta).unwrap();
            let s = FitState {
                model: m,
                poses: poses.clone(),
            };
            prior_rows(&problem, &s, false)
        };
        let (plus, minus) = (at(h), at(-h));
        for (k, (_, a)) in rows.iter().enumerate() {
            let fd = (plus[k].0 - minus[k].0) / (2.0 * h);
            assert!(
                (fd - a[slot]).abs() <= 1e-7 * (1.0 + a[slot].abs()),
                "row {k}, {name}: {fd} vs {}",
                a[slot]
            );
        }
    }
}

/// The calibration options with the map (at `values`) first in the base.
fn with_map(model: &Model, names: &[String], values: &[f64]) -> CalibrateOptions {
    let mut base = Model::standard(&SensorModel::pinhole(8.0, 0.0, 0.0));
    base = base.with_stage(0, Box::new(truth().1)).unwrap();
    for (n, v) in names.iter().zip(values) {
        base.set(n, *v).unwrap();
    }
    let _ = model;
    CalibrateOptions {
        base,
        ..CalibrateOptions::default()
    }
}

/// The σ of a refined map coefficient: its block of the joint covariance,
/// split off the estimate's by the calibration.
fn block_std(result: &psdcal_calib::CalibrationResult, name: &str) -> f64 {
    let block = result.block.as_ref().expect("the refined block");
    let k = block
        .parameters
        .iter()
        .position(|(n, _)| n == name)
        .expect("a block parameter");
    let matrix = block.matrix.as_ref().expect("refined: its own covariance");
    matrix[(k, k)].sqrt()
}

#[test]
fn a_very_tight_prior_gives_the_fixed_map_s_answer() {
    let (model, map) = truth();
    let (data, _) = scene(&model, 5, 1e-3);
    let names = names(&map);
    let values: Vec<f64> = names.iter().map(|n| model.get(n).unwrap() + 2e-3).collect();
    let options = with_map(&model, &names, &values);
    let held = calibrate(&data, &options).unwrap();
    // σ_prior = 1 nm on every coefficient.
    let tight = scan_covariance(&names, 1e-6);
    let refined = calibrate(
        &data,
        &CalibrateOptions {
            prior: Some(tight.clone()),
            ..options.clone()
        },
    )
    .unwrap();
    // How far the prior lets θ move: G Σ Gᵀ, G = ∂θ̂/∂m at the held fit.
    let g = carry_fixed_covariance(
        &data,
        &held.model,
        &held.poses,
        &options.refine,
        &held.covariance.parameters,
        &tight,
    )
    .unwrap()
    .sensitivity;
    let moved = &g * tight.matrix() * g.transpose();
    for (i, t) in options.refine.free_names().iter().enumerate() {
        let d = refined.model.get(t).unwrap() - held.model.get(t).unwrap();
        let tol = 5.0 * moved[(i, i)].sqrt() + 1e-10;
        assert!(d.abs() <= tol, "{t}: moved {d:e}, allowed {tol:e}");
        // The covariance is the held fit's own (the map is pinned).
        let (a, b) = (
            refined.covariance.std(t).unwrap(),
            held.covariance.std(t).unwrap(),
        );
        assert!((a / b - 1.0).abs() < 1e-3, "σ({t}) {a:e} vs {b:e}");
    }
    for (k, n) in names.iter().enumerate() {
        let d = refined.model.get(n).unwrap() - values[k];
        assert!(d.abs() <= 5e-6, "{n} moved {d:e}");
        // Free, with a σ no larger than the prior's.
        let sd = block_std(&refined, n);
        assert!(sd <= 1e-6 * (1.0 + 1e-9), "σ({n}) {sd:e}");
    }
    assert!(refined.free.len() == options.refine.free_names().len() + names.len());
}

/// RMS over the active area (41 × 41) of two maps' displacement difference, mm.
fn map_error(map: &PsdMap, a: &[f64], b: &[f64]) -> f64 {
    let mut s = 0.0;
    for i in 0..41 {
        for j in 0..41 {
            let m = Vector2::new(-4.3 + 8.6 * i as f64 / 40.0, -4.3 + 8.6 * j as f64 / 40.0);
            s += (map.displacement(a, &m) - map.displacement(b, &m)).norm_squared();
        }
    }
    (s / 1681.0).sqrt()
}

/// A map biased by a draw from its own covariance (σ 3 µm per
/// coefficient: a sparse, noisy scan) comes closer to the true field when
/// refined (pooled over 8 seeds), and every coefficient's σ shrinks.
#[test]
fn refining_a_biased_map_moves_it_towards_the_truth() {
    let (model, map) = truth();
    let names = names(&map);
    let true_values: Vec<f64> = names.iter().map(|n| model.get(n).unwrap()).collect();
    let cov = scan_covariance(&names, 3e-3);
    let chol = cov.matrix().clone().cholesky().unwrap().l();
    let (mut before, mut after) = (0.0, 0.0);
    for seed in 0..8u64 {
        let (data, _) = scene(&model, 100 + seed, 1e-3);
        let mut rng = ChaCha8Rng::seed_from_u64(900 + seed);
        let z = DVector::from_iterator(
            names.len(),
            (0..names.len()).map(|_| Normal::new(0.0, 1.0).unwrap().sample(&mut rng)),
        );
        let biased: Vec<f64> = (DVector::from_column_slice(&true_values) + &chol * z)
            .iter()
            .copied()
            .collect();
        let options = CalibrateOptions {
            prior: Some(cov.clone()),
            ..with_map(&model, &names, &biased)
        };
        let refined = calibrate(&data, &options).unwrap();
        let fitted: Vec<f64> = names
            .iter()
            .map(|n| refined.model.get(n).unwrap())
            .collect();
        before += map_error(&map, &biased, &true_values).powi(2);
        after += map_error(&map, &fitted, &true_values).powi(2);
        for n in &names {
            let (post, prior) = (block_std(&refined, n), cov.std(n).unwrap());
            assert!(post <= prior * (1.0 + 1e-9), "σ({n}) {post:e} > {prior:e}");
        }
    }
    let (before, after) = ((before / 8.0).sqrt(), (after / 8.0).sqrt());
    eprintln!("map error vs truth: held {before:e} mm, refined {after:e} mm");
    assert!(after < 0.8 * before, "held {before:e}, refined {after:e}");
}
