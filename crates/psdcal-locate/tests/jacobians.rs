//! Every analytic Jacobian of psdcal-locate against central finite
//! differences (relative 1e-6 of the Jacobian block's size).

mod support;

use nalgebra::{DMatrix, Matrix2, Vector2, Vector3};
use psdcal_locate::{
    alpha_from_ray, angle_of_arrival, angle_of_arrival_with_jacobians, intersect_plane,
    triangulate, CalibratedSensor, LocateOptions, Measurement, ParameterCovariance, Plane,
    WorldRay,
};
use psdcal_model::psd::electrode_currents;
use psdcal_model::stages::Gains;
use psdcal_model::{ChannelGains, Param, PsdGeometry, SensorModel};
use support::{models, rel, sensor_points};

const TOL: f64 = 1e-6;

/// Finite-difference step of each parameter: moves a point 4 mm from the
/// centre by about 1e-5 mm.
fn step(p: Param) -> f64 {
    match p {
        Param::F => 1e-5,
        Param::Cx | Param::Cy | Param::Skew => 1e-6,
        Param::K1 | Param::L1 | Param::P1 | Param::P2 => 1e-6,
        Param::K2 | Param::L2 => 4e-8,
        Param::K3 => 2e-9,
    }
}

#[test]
fn aoa_jacobians_wrt_model_and_point() {
    let mut worst: f64 = 0.0;
    for (name, model) in models() {
        for m in sensor_points() {
            let (_, jac) =
                angle_of_arrival_with_jacobians(&psdcal_model::Model::standard(&model), &m)
                    .unwrap();
            let ray = |model: &SensorModel, m: &Vector2<f64>| {
                angle_of_arrival(&psdcal_model::Model::standard(model), m)
                    .unwrap()
                    .ray_ab
            };
            let scale = jac.ray_wrt_model.abs().max();
            for p in Param::ALL {
                let h = step(p);
                let (mut up, mut down) = (model, model);
                up.set(p, model.get(p) + h);
                down.set(p, model.get(p) - h);
                let fd = (ray(&up, &m) - ray(&down, &m)) / (2.0 * h);
                for r in 0..2 {
                    // Scale per column: the column's own size, or the block's.
                    let col = jac.ray_wrt_model.column(p.index()).abs().max();
                    let e = rel(
                        jac.ray_wrt_model[(r, p.index())],
                        fd[r],
                        col.max(1e-3 * scale),
                    );
                    worst = worst.max(e);
                    assert!(e < TOL, "{name} at {m:?}: ∂ray/∂{p} row {r}: rel {e:e}");
                }
            }
            let scale = jac.ray_wrt_measured.abs().max();
            for c in 0..2 {
                let h = 1e-6;
                let mut e = Vector2::zeros();
                e[c] = h;
                let fd = (ray(&model, &(m + e)) - ray(&model, &(m - e))) / (2.0 * h);
                for r in 0..2 {
                    let err = rel(jac.ray_wrt_measured[(r, c)], fd[r], scale);
                    worst = worst.max(err);
                    assert!(err < TOL, "{name} at {m:?}: ∂ray/∂m ({r},{c}): rel {err:e}");
                }
            }
            // ∂α/∂(a, b).
            let ab = angle_of_arrival(&psdcal_model::Model::standard(&model), &m)
                .unwrap()
                .ray_ab;
            for c in 0..2 {
                let h = 1e-7;
                let mut e = Vector2::zeros();
                e[c] = h;
                let fd = (alpha_from_ray(&(ab + e)) - alpha_from_ray(&(ab - e))) / (2.0 * h);
                for r in 0..2 {
                    let err = rel(jac.alpha_wrt_ray[(r, c)], fd[r], 1.0);
                    assert!(err < TOL, "∂α/∂ray ({r},{c}): {err:e}");
                }
            }
        }
    }
    println!("worst relative error of the AoA Jacobians: {worst:.2e}");
}

#[test]
fn gain_columns_of_the_propagation() {
    // For amplitude input the calibration's gain entries act through
    // ∂ray/∂m · ∂m/∂g: check them by propagating a unit variance of one gain.
    let geometry = PsdGeometry::default();
    let gains = ChannelGains {
        x2: 1.03,
        y1: 0.96,
        y2: 1.02,
    };
    let model = SensorModel::paper_lens2();
    for m in sensor_points() {
        let amps = electrode_currents(&geometry, &m, 1.0).apply_gains(&gains);
        for k in 0..3 {
            let cov = ParameterCovariance::new(
                vec![Gains::parameters()[k].name.clone()],
                DMatrix::from_element(1, 1, 1.0),
            )
            .unwrap();
            let sensor = CalibratedSensor::new(model, geometry)
                .with_gains(gains)
                .with_covariance(cov);
            let est = sensor
                .aoa(&Measurement::Amplitudes(amps), &LocateOptions::default())
                .unwrap();
            // With Var(g_k) = 1, Σ_ray = j jᵀ with j = ∂ray/∂g_k.
            let ray_at = |g: f64| {
                let mut gg = gains;
                match k {
                    0 => gg.x2 = g,
                    1 => gg.y1 = g,
                    _ => gg.y2 = g,
                }
                CalibratedSensor::new(model, geometry)
                    .with_gains(gg)
                    .aoa(&Measurement::Amplitudes(amps), &LocateOptions::default())
                    .unwrap()
                    .aoa
                    .ray_ab
            };
            let g0 = gains.to_array()[k];
            let h = 1e-6;
            let j = (ray_at(g0 + h) - ray_at(g0 - h)) / (2.0 * h);
            let expected = j * j.transpose();
            let c = est.ray_covariance_calibration;
            let scale = expected.abs().max().max(1e-20);
            assert!(
                (c - expected).abs().max() / scale < 1e-6,
                "gain {k} at {m:?}: {c} vs {expected}"
            );
        }
    }
}

#[test]
fn plane_intersection_jacobian() {
    let planes = [
        Plane::parallel(5000.0).unwrap(),
        Plane::new(Vector3::new(0.2, -0.3, 1.0), 4000.0).unwrap(),
        Plane::new(Vector3::new(0.0, -1.0, 0.1), 1500.0).unwrap(),
    ];
    for plane in &planes {
        for ab in [
            Vector2::new(0.0, 0.0),
            Vector2::new(0.3, -0.2),
            Vector2::new(-0.25, -0.4),
        ] {
            let Ok(hit) = intersect_plane(plane, &ab) else {
                continue;
            };
            let scale = hit.wrt_ray.abs().max();
            for c in 0..2 {
                let h = 1e-7;
                let mut e = Vector2::zeros();
                e[c] = h;
                let fd = (intersect_plane(plane, &(ab + e)).unwrap().position
                    - intersect_plane(plane, &(ab - e)).unwrap().position)
                    / (2.0 * h);
                for r in 0..3 {
                    let err = rel(hit.wrt_ray[(r, c)], fd[r], scale);
                    assert!(
                        err < TOL,
                        "plane {plane:?} ray {ab:?}: ({r},{c}) rel {err:e}"
                    );
                }
            }
        }
    }
}

/// ∂P/∂(a_i, b_i) of the least-squares intersection against re-solving with
/// perturbed rays (consistent rays: the derivative is exact there).
#[test]
fn triangulation_jacobian_wrt_rays() {
    let rig = support::three_sensor_rig(SensorModel::paper_lens2());
    let emitter = Vector3::new(150.0, -200.0, 30.0);
    let covariances = [
        Matrix2::new(4e-8, 1e-8, 1e-8, 2e-8),
        Matrix2::new(1e-8, 0.0, 0.0, 3e-8),
        Matrix2::new(2e-8, -5e-9, -5e-9, 2e-8),
    ];
    for weighted in [true, false] {
        let rays: Vec<WorldRay> = rig
            .sensors()
            .iter()
            .zip(covariances)
            .enumerate()
            .map(|(k, (s, c))| {
                let p = s.world_from_sensor.inverse().transform(&emitter);
                WorldRay {
                    sensor: s.id.clone(),
                    world_from_sensor: s.world_from_sensor,
                    ray_ab: Vector2::new(p.x / p.z, p.y / p.z),
                    // A zero covariance on one ray makes the fit unweighted.
                    covariance_ab: if !weighted && k == 0 {
                        Matrix2::zeros()
                    } else {
                        c
                    },
                }
            })
            .collect();
        let options = LocateOptions::default();
        let t = triangulate(&rays, &options).unwrap();
        assert_eq!(t.weighted, weighted);
        assert!((t.position - emitter).norm() < 1e-9);
        for (i, j) in t.wrt_rays.iter().enumerate() {
            let scale = j.abs().max();
            for c in 0..2 {
                let h = 1e-8;
                let solve = |sign: f64| {
                    let mut r = rays.clone();
                    r[i].ray_ab[c] += sign * h;
                    triangulate(&r, &options).unwrap().position
                };
                let fd = (solve(1.0) - solve(-1.0)) / (2.0 * h);
                for r in 0..3 {
                    let err = rel(j[(r, c)], fd[r], scale);
                    assert!(
                        err < TOL,
                        "weighted {weighted}, ray {i}: ∂P/∂z ({r},{c}) = {} vs {} (rel {err:e})",
                        j[(r, c)],
                        fd[r]
                    );
                }
            }
        }
    }
}
