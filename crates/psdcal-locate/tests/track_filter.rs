//! The constant-velocity filter (`track_filter`) against independent
//! computations: without process noise its final state and covariance are
//! the batch weighted least squares of the linear trajectory; with the
//! model true its NEES is χ²₃ (Monte Carlo); the gate is χ²₃'s 0.9999
//! quantile (numerical integration); odd inputs give no NaN.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use psdcal_locate::track_filter::{transition, GATE_D2_9999};
use psdcal_locate::{CvFilter, CvOptions, FilterStep};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

fn normal3(rng: &mut ChaCha8Rng) -> Vector3<f64> {
    Vector3::new(
        rng.sample(StandardNormal),
        rng.sample(StandardNormal),
        rng.sample(StandardNormal),
    )
}

/// A random symmetric positive definite covariance, σ of 5–25 mm.
fn random_covariance(rng: &mut ChaCha8Rng) -> Matrix3<f64> {
    let a = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0));
    let q = a.qr().q();
    let d = Matrix3::from_diagonal(&Vector3::from_fn(|_, _| {
        rng.random_range(5.0f64..25.0).powi(2)
    }));
    q * d * q.transpose()
}

#[test]
fn zero_process_noise_gives_the_batch_least_squares() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let options = CvOptions {
        accel_sigma_mm_s2: 0.0,
        gate_d2: f64::INFINITY,
        max_gap_s: 1e9,
        ..CvOptions::default()
    };
    let sv = options.initial_speed_sigma_mm_s;
    let mut filter = CvFilter::new(options);
    let p0 = Vector3::new(100.0, -2000.0, 3000.0);
    let v = Vector3::new(600.0, -300.0, 50.0);
    // Uneven times.
    let mut t = 0.0;
    let mut info = Matrix6::zeros();
    let mut rhs = Vector6::zeros();
    let mut rows = Vec::new();
    for i in 0..40 {
        t += 0.03 + 0.04 * (i % 3) as f64;
        let r = random_covariance(&mut rng);
        let z = p0 + v * t + r.cholesky().unwrap().l() * normal3(&mut rng);
        let step = filter.step(t, Some((z, r)));
        assert_eq!(
            step,
            if i == 0 {
                FilterStep::Started
            } else {
                FilterStep::Updated
            }
        );
        rows.push((t, z, r));
    }
    let t_end = t;
    // Batch: unknowns (p(t_end), v); z_i = p + (t_i − t_end) v; the prior
    // v ~ N(0, σ_v0² I) of the track's start.
    for (t, z, r) in &rows {
        let mut h = nalgebra::Matrix3x6::zeros();
        h.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::identity());
        h.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(Matrix3::identity() * (t - t_end)));
        let w = r.try_inverse().unwrap();
        info += h.transpose() * w * h;
        rhs += h.transpose() * w * z;
    }
    for i in 3..6 {
        info[(i, i)] += 1.0 / (sv * sv);
    }
    let cov = info.try_inverse().unwrap();
    let x = cov * rhs;
    let state = filter.state().unwrap();
    for i in 0..6 {
        let scale = cov[(i, i)].sqrt();
        assert!(
            (state.x[i] - x[i]).abs() < 1e-6 * scale,
            "state {i}: {} vs {}",
            state.x[i],
            x[i]
        );
        for j in 0..6 {
            let s = (cov[(i, i)] * cov[(j, j)]).sqrt();
            assert!(
                (state.p[(i, j)] - cov[(i, j)]).abs() < 1e-7 * s,
                "P {i},{j}"
            );
        }
    }
}

/// The continuous model's `Q` equals the integral `∫ Φ(τ) G q Gᵀ Φ(τ)ᵀ dτ`
/// computed by the midpoint rule.
#[test]
fn the_process_noise_is_the_integral_of_the_continuous_model() {
    let (dt, q) = (0.05, 2.5e5);
    let (f, qm) = transition(dt, q);
    let n = 20_000;
    let mut integral = Matrix6::zeros();
    for k in 0..n {
        let tau = (k as f64 + 0.5) * dt / n as f64;
        let (phi, _) = transition(tau, 0.0);
        let g = phi.fixed_columns::<3>(3).into_owned();
        integral += g * g.transpose() * (q * dt / n as f64);
    }
    assert!(
        (qm - integral).norm() < 1e-6 * qm.norm(),
        "{qm} vs {integral}"
    );
    assert_eq!(f[(0, 3)], dt);
}

#[test]
fn nees_is_chi_squared_with_three_degrees_of_freedom() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let options = CvOptions {
        accel_sigma_mm_s2: 800.0,
        gate_d2: f64::INFINITY,
        ..CvOptions::default()
    };
    let q = options.accel_sigma_mm_s2.powi(2);
    let dt = 0.05;
    let (f, qm) = transition(dt, q);
    let lq = qm.cholesky().unwrap().l();
    let (mut sum, mut n, mut inside) = (0.0, 0usize, 0usize);
    for _ in 0..300 {
        let mut filter = CvFilter::new(options);
        // The start's prior is the truth's law: v ~ N(0, σ_v0² I).
        let mut x = Vector6::zeros();
        for i in 3..6 {
            x[i] = options.initial_speed_sigma_mm_s * rng.sample::<f64, _>(StandardNormal);
        }
        for k in 0..80 {
            if k > 0 {
                let w = Vector6::from_fn(|_, _| rng.sample(StandardNormal));
                x = f * x + lq * w;
            }
            let r = random_covariance(&mut rng);
            let z = x.fixed_rows::<3>(0) + r.cholesky().unwrap().l() * normal3(&mut rng);
            filter.step(k as f64 * dt, Some((z, r)));
            let s = filter.state().unwrap();
            let e = s.position() - x.fixed_rows::<3>(0);
            let d2 = e.dot(&(s.position_covariance().try_inverse().unwrap() * e));
            sum += d2;
            n += 1;
            if d2 <= 11.344_866_730_144_373 {
                inside += 1;
            }
        }
    }
    let mean = sum / n as f64;
    // 24 000 samples (correlated in time): the mean within ±0.12 of 3.
    assert!((mean - 3.0).abs() < 0.12, "mean NEES {mean}");
    let fraction = inside as f64 / n as f64;
    assert!(
        (fraction - 0.99).abs() < 0.004,
        "inside the 99 % ellipsoid: {fraction}"
    );
}

/// χ²₃'s CDF at the gate by Simpson's rule on its density (in `u = √x`,
/// where the integrand is smooth).
#[test]
fn the_gate_is_the_chi_squared_quantile() {
    let density = |x: f64| (x / (2.0 * std::f64::consts::PI)).sqrt() * (-x / 2.0).exp();
    let pdf = |u: f64| density(u * u) * 2.0 * u;
    let n = 200_000;
    let end = GATE_D2_9999.sqrt();
    let h = end / n as f64;
    let mut s = pdf(0.0) + pdf(end);
    for k in 1..n {
        s += pdf(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    let cdf = s * h / 3.0;
    assert!((cdf - 0.9999).abs() < 1e-8, "{cdf}");
}

#[test]
fn outliers_gaps_and_odd_inputs() {
    let options = CvOptions {
        max_missed: 3,
        max_gap_s: 0.5,
        ..CvOptions::default()
    };
    let r = Matrix3::identity() * 100.0;
    let z = Vector3::new(0.0, 0.0, 3000.0);
    let mut f = CvFilter::new(options);
    assert_eq!(f.step(0.0, None), FilterStep::Lost);
    assert_eq!(f.step(0.05, Some((z, r))), FilterStep::Started);
    assert_eq!(f.step(0.05, Some((z, r))), FilterStep::Updated); // Δt = 0
                                                                 // An outlier 5 m away is gated; the state stays finite.
    let far = z + Vector3::new(5000.0, 0.0, 0.0);
    assert_eq!(f.step(0.1, Some((far, r))), FilterStep::Gated);
    assert!((f.state().unwrap().position() - z).norm() < 100.0);
    // Not a covariance, NaN: no measurement.
    let bad = Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0);
    assert_eq!(f.step(0.15, Some((z, bad))), FilterStep::Predicted);
    let nan = Vector3::new(f64::NAN, 0.0, 0.0);
    assert_eq!(f.step(0.2, Some((nan, r))), FilterStep::Predicted);
    // The fourth window in a row without a used measurement: the track is
    // dropped and the measurement starts a new one.
    assert_eq!(f.step(0.25, Some((far, r))), FilterStep::Started);
    assert!((f.state().unwrap().position() - far).norm() < 1e-9);
    // A gap drops the track.
    assert_eq!(f.step(2.0, None), FilterStep::Lost);
    assert!(f.state().is_none());
    // Backwards in time: dropped, restarted.
    assert_eq!(f.step(0.3, Some((z, r))), FilterStep::Started);
    assert_eq!(f.step(0.1, Some((z, r))), FilterStep::Started);
    let s = f.state().unwrap();
    assert!(s.x.iter().chain(s.p.iter()).all(|v| v.is_finite()));
}
