//! Acceptance: the reported 3-D covariance of a position agrees with the
//! empirical covariance over seeded Monte Carlo trials within 25 %.
//!
//! With N trials the sample standard deviation scatters by about
//! 1/√(2(N − 1)) (1.6 % for N = 2000), so 25 % leaves a wide margin for the
//! linearisation and still fails on a wrong covariance (a missing factor,
//! a wrong weighting or a transposed Jacobian is off by far more).

mod support;

use nalgebra::{Matrix2, Matrix3, SymmetricEigen, Vector2, Vector3};
use psdcal_locate::{triangulate, CalibratedSensor, LocateOptions, Measurement, Plane, WorldRay};
use psdcal_model::{PsdGeometry, SensorModel};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

const TRIALS: u64 = 2000;

fn empirical_covariance(samples: &[Vector3<f64>]) -> Matrix3<f64> {
    let n = samples.len() as f64;
    let mean: Vector3<f64> = samples.iter().sum::<Vector3<f64>>() / n;
    samples
        .iter()
        .map(|s| (s - mean) * (s - mean).transpose())
        .sum::<Matrix3<f64>>()
        / (n - 1.0)
}

/// Per axis σ ratio, and the eigenvalues of `Σ_rep^{-1/2} Σ_emp Σ_rep^{-1/2}`
/// (variance ratios along every direction): all must be within 25 % in σ.
fn compare(name: &str, empirical: &Matrix3<f64>, reported: &Matrix3<f64>, dims: usize) {
    for k in 0..dims {
        let ratio = (empirical[(k, k)] / reported[(k, k)]).sqrt();
        println!("{name}: axis {k}: σ empirical / reported = {ratio:.3}");
        assert!(
            (ratio - 1.0).abs() < 0.25,
            "{name}: axis {k}: ratio {ratio}"
        );
    }
    if dims == 3 {
        let eig = SymmetricEigen::new(*reported);
        let inv_sqrt = eig.eigenvectors
            * Matrix3::from_diagonal(&eig.eigenvalues.map(|l| 1.0 / l.sqrt()))
            * eig.eigenvectors.transpose();
        let whitened = inv_sqrt * empirical * inv_sqrt;
        let ratios = SymmetricEigen::new(whitened).eigenvalues.map(f64::sqrt);
        println!("{name}: σ ratios along the principal directions {ratios:.3?}");
        for r in ratios.iter() {
            assert!((r - 1.0).abs() < 0.25, "{name}: whitened σ ratio {r}");
        }
    }
}

/// Draws `N(0, C)` for a 2×2 covariance.
fn sample(c: &Matrix2<f64>, rng: &mut ChaCha8Rng) -> Vector2<f64> {
    let l = c.cholesky().expect("positive definite").l();
    let z = Vector2::new(StandardNormal.sample(rng), StandardNormal.sample(rng));
    l * z
}

#[test]
fn triangulation_covariance_matches_monte_carlo() {
    let rig = support::three_sensor_rig(SensorModel::paper_lens2());
    let emitter = Vector3::new(120.0, -90.0, 150.0);
    // Anisotropic, correlated ray noise of a few 1e-4 (≈ 1 µm on an 8 mm lens
    // is 1.25e-4), different per sensor.
    let covariances = [
        Matrix2::new(4e-8, 1.5e-8, 1.5e-8, 2e-8),
        Matrix2::new(1e-8, 0.0, 0.0, 6e-8),
        Matrix2::new(3e-8, -1e-8, -1e-8, 2e-8),
    ];
    let truth: Vec<Vector2<f64>> = rig
        .sensors()
        .iter()
        .map(|s| {
            let p = s.world_from_sensor.inverse().transform(&emitter);
            Vector2::new(p.x / p.z, p.y / p.z)
        })
        .collect();
    for (label, use_sensors, weight_rays) in [
        ("three sensors", vec![0, 1, 2], true),
        ("three sensors, unweighted", vec![0, 1, 2], false),
        ("two sensors", vec![0, 2], true),
    ] {
        let rays_of = |rng: Option<&mut ChaCha8Rng>| -> Vec<WorldRay> {
            let mut rng = rng;
            use_sensors
                .iter()
                .map(|&k| {
                    let s = &rig.sensors()[k];
                    let noise = match rng.as_deref_mut() {
                        Some(r) => sample(&covariances[k], r),
                        None => Vector2::zeros(),
                    };
                    WorldRay {
                        sensor: s.id.clone(),
                        world_from_sensor: s.world_from_sensor,
                        ray_ab: truth[k] + noise,
                        covariance_ab: covariances[k],
                    }
                })
                .collect()
        };
        let options = LocateOptions {
            weight_rays,
            ..LocateOptions::default()
        };
        let reported = triangulate(&rays_of(None), &options).unwrap().covariance;
        let positions: Vec<Vector3<f64>> = (0..TRIALS)
            .map(|trial| {
                let mut rng = ChaCha8Rng::seed_from_u64(7_000 + trial);
                triangulate(&rays_of(Some(&mut rng)), &options)
                    .unwrap()
                    .position
            })
            .collect();
        compare(label, &empirical_covariance(&positions), &reported, 3);
    }
}

#[test]
fn plane_position_covariance_matches_monte_carlo() {
    // Point noise of 2 µm on the PSD, lens 2, on a tilted plane 3 m away.
    let sigma = 2e-3;
    let model = SensorModel::paper_lens2();
    let sensor = CalibratedSensor::new(model, PsdGeometry::default());
    let plane = Plane::new(Vector3::new(0.3, -0.2, 1.0), 3000.0).unwrap();
    let options = LocateOptions {
        point_sigma_mm: sigma,
        ..LocateOptions::default()
    };
    for m in [
        Vector2::new(0.0, 0.0),
        Vector2::new(3.5, -2.5),
        Vector2::new(-4.0, 4.0),
    ] {
        let reported = sensor
            .locate_on_plane(&Measurement::Point(m), &plane, &options)
            .unwrap()
            .covariance();
        let positions: Vec<Vector3<f64>> = (0..TRIALS)
            .map(|trial| {
                let mut rng = ChaCha8Rng::seed_from_u64(11_000 + trial);
                let z: [f64; 2] = [
                    StandardNormal.sample(&mut rng),
                    StandardNormal.sample(&mut rng),
                ];
                let noisy = m + Vector2::new(z[0], z[1]) * sigma;
                sensor
                    .locate_on_plane(
                        &Measurement::Point(noisy),
                        &plane,
                        &LocateOptions::default(),
                    )
                    .unwrap()
                    .intersection
                    .position
            })
            .collect();
        // The position lies on the plane: its covariance has rank 2, so
        // compare the three axes (all vary on a tilted plane), not whitened.
        compare(
            &format!("plane at {m:?}"),
            &empirical_covariance(&positions),
            &reported,
            2,
        );
        let emp = empirical_covariance(&positions);
        let ratio_z = (emp[(2, 2)] / reported[(2, 2)]).sqrt();
        assert!((ratio_z - 1.0).abs() < 0.25, "Z: ratio {ratio_z}");
    }
}
