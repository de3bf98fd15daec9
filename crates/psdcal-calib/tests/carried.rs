//! A fixed PSD map's covariance carried into the estimate (docs/model.md
//! §8.3, `psdcal_calib::carry_fixed_covariance`): the sensitivity
//! `G = ∂θ̂/∂m` against finite differences of the refinement itself (the
//! map's coefficients moved one at a time and the data refitted), and the
//! carried covariance against its formula `C_θ + G C_m Gᵀ`.

mod support;

use nalgebra::{DMatrix, Vector2};
use psdcal_calib::{carry_fixed_covariance, covariance, refine, CalibrationData, RefineOptions};
use psdcal_model::stages::{MapBasis, MapFrame, PsdMap};
use psdcal_model::{Model, Param, ParameterCovariance, SensorModel, Stage};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::Normal;

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

fn scene(model: &Model) -> (CalibrationData, Vec<psdcal_model::Pose>) {
    let template = support::template(14);
    let mut rng = ChaCha8Rng::seed_from_u64(21);
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
    psdcal_testkit::add_noise(&mut points, &Normal::new(0.0, 1e-3).unwrap(), &mut rng);
    (support::calibration_data(&template, &[], points), poses)
}

#[test]
fn the_sensitivity_is_the_refit_s_derivative_and_the_covariance_its_formula() {
    let (model, map) = truth();
    let (data, poses) = scene(&model);
    let options = RefineOptions {
        free: vec![Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2],
        cost_tolerance: 1e-15,
        step_tolerance: 1e-15,
        ..RefineOptions::default()
    };
    let base = refine(&data, model.clone(), &poses, &options).unwrap();
    let cov = covariance(&data, &base, &options).unwrap();
    let names: Vec<String> = map.parameters().iter().map(|p| p.name.clone()).collect();
    // A map covariance: 2 µm² on the diagonal, correlated neighbours.
    let n = names.len();
    let cm = DMatrix::from_fn(n, n, |i, j| 4e-6 * 0.5f64.powi((i as i32 - j as i32).abs()));
    let fixed = ParameterCovariance::new(names.clone(), cm.clone()).unwrap();
    let carried = carry_fixed_covariance(
        &data,
        &base.model,
        &base.poses,
        &options,
        &cov.parameters,
        &fixed,
    )
    .unwrap();
    let theta = options.free_names();
    let h = 1e-4; // mm: the data move by ≈ h, far above the 1e-15 tolerance
    let mut checked = 0;
    for (k, name) in names.iter().enumerate().step_by(3) {
        let mut moved = base.model.clone();
        moved.set(name, base.model.get(name).unwrap() + h).unwrap();
        let r = refine(&data, moved, &base.poses, &options).unwrap();
        for (i, t) in theta.iter().enumerate() {
            let fd = (r.model.get(t).unwrap() - base.model.get(t).unwrap()) / h;
            let g = carried.sensitivity[(i, k)];
            // Within 2 % (first order in h), or, for a derivative the refit
            // resolves only to its convergence (a coefficient that cx, cy
            // absorb exactly), an error below 1 % of θ's own σ when scaled
            // by the coefficient's σ: negligible in the carried covariance.
            let (sd_m, sd_t) = (cm[(k, k)].sqrt(), cov.parameters.std(t).unwrap());
            assert!(
                (fd - g).abs() <= 0.02 * g.abs() || (fd - g).abs() * sd_m <= 0.01 * sd_t,
                "∂{t}/∂{name}: refit {fd:e}, G {g:e}"
            );
            checked += usize::from(g.abs() * sd_m > 0.1 * sd_t);
        }
    }
    // Some of the checked derivatives matter (move θ by > 0.1 σ per σ_m).
    assert!(checked >= 3, "{checked}");
    let g = &carried.sensitivity;
    let expected = cov.parameters.matrix() + g * &cm * g.transpose();
    assert!((carried.parameters.matrix() - &expected).norm() <= 1e-12 * expected.norm());
    assert!((&carried.cross - &cm * g.transpose()).norm() <= 1e-12 * carried.cross.norm());
    // The map's uncertainty does inflate f's σ.
    assert!(carried.parameters.std("f").unwrap() > cov.parameters.std("f").unwrap());
}
