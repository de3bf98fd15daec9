//! The positioning metrics (`psdcal_locate::evaluate`) against independent
//! computations on seeded data (1e-9 relative), and the honesty check: with
//! a correct covariance, 0.95 ± 0.03 of 2 000 simulated truths lie inside
//! their estimate's 95 % ellipsoid (the binomial σ is √(0.95·0.05/2000) =
//! 0.0049, so ±0.03 is six σ; a covariance off by a factor 1.5 in σ gives
//! 0.67 and fails).

use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use psdcal_locate::{
    evaluate_angles, evaluate_positions, percentile, AnglePair, LocateError, PositionPair,
    CHI2_95_2D, CHI2_95_3D,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-9 * b.abs().max(1e-300),
        "{what}: {a} against {b}"
    );
}

/// The regularised lower incomplete gamma function P(a, x) by its series
/// `x^a e^-x / Γ(a+1) · Σ_k x^k / ((a+1)…(a+k))`, for a = 1 and 3/2.
fn gamma_p(a: f64, x: f64) -> f64 {
    let gamma_a1 = if a == 1.0 {
        1.0
    } else {
        // Γ(5/2) = (3/2)(1/2)√π.
        0.75 * std::f64::consts::PI.sqrt()
    };
    let (mut term, mut sum) = (1.0, 1.0);
    for k in 1..400 {
        term *= x / (a + k as f64);
        sum += term;
        if term < 1e-18 * sum {
            break;
        }
    }
    (a * x.ln() - x).exp() / gamma_a1 * sum
}

/// The χ² quantile of 0.95 with `dof` degrees of freedom by bisection on
/// P(dof/2, x/2) = 0.95.
fn chi2_95(dof: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 50.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if gamma_p(dof / 2.0, mid / 2.0) < 0.95 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn chi_square_quantiles_are_right() {
    close(CHI2_95_3D, chi2_95(3.0), "χ²₃");
    close(CHI2_95_2D, chi2_95(2.0), "χ²₂");
    close(CHI2_95_2D, -2.0 * 0.05f64.ln(), "χ²₂ closed form");
}

/// The q-quantile by the 1-based textbook form of definition 7: rank
/// `1 + (n−1) q`, `(1 − g) x_j + g x_{j+1}`.
fn quantile_1_based(values: &[f64], q: f64) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let rank = 1.0 + (v.len() as f64 - 1.0) * q;
    let j = rank.floor() as usize; // 1-based
    let g = rank - j as f64;
    let xj = v[j - 1];
    let xj1 = if j < v.len() { v[j] } else { v[j - 1] };
    (1.0 - g) * xj + g * xj1
}

#[test]
fn percentiles_match_known_values() {
    // NumPy: np.percentile([1, 2, 3, 4], [50, 75, 95]) = 2.5, 3.25, 3.85.
    let v = [1.0, 2.0, 3.0, 4.0];
    assert_eq!(percentile(&v, 0.5), Some(2.5));
    assert_eq!(percentile(&v, 0.75), Some(3.25));
    close(percentile(&v, 0.95).unwrap(), 3.85, "p95");
    assert_eq!(percentile(&[7.0], 0.95), Some(7.0));
    assert_eq!(percentile(&[], 0.5), None);
}

fn random_covariance(rng: &mut ChaCha8Rng, scale: f64) -> Matrix3<f64> {
    let a = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0) * scale);
    a * a.transpose() + Matrix3::identity() * (0.05 * scale * scale)
}

fn draw(l: &Matrix3<f64>, rng: &mut ChaCha8Rng) -> Vector3<f64> {
    l * Vector3::from_fn(|_, _| StandardNormal.sample(rng))
}

/// `n` emitters in a room, estimates drawn from their own covariance
/// (scaled by `wrong` against the reported one), plus a bias.
fn simulated(n: usize, seed: u64, wrong: f64) -> Vec<PositionPair> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let truth = Vector3::new(
                rng.random_range(-2000.0..2000.0),
                rng.random_range(-2000.0..2000.0),
                rng.random_range(0.0..1500.0),
            );
            let scale = rng.random_range(1.0..10.0);
            let c = random_covariance(&mut rng, scale);
            let l = c.cholesky().unwrap().l();
            let estimate = truth + draw(&l, &mut rng) * wrong;
            PositionPair {
                truth,
                estimate,
                covariance: Some(c),
            }
        })
        .collect()
}

#[test]
fn every_position_metric_equals_an_independent_computation() {
    for (n, seed) in [(1usize, 1u64), (2, 2), (17, 3), (500, 4)] {
        let mut pairs = simulated(n, seed, 1.0);
        for p in &mut pairs {
            p.estimate += Vector3::new(1.5, -0.5, 2.0);
        }
        let ev = evaluate_positions(&pairs).unwrap();
        let s = &ev.stats;
        // Independent: plain loops over the components.
        let mut d = Vec::new();
        let mut h = Vec::new();
        let (mut bx, mut by, mut bz) = (0.0, 0.0, 0.0);
        for p in &pairs {
            let (ex, ey, ez) = (
                p.estimate[0] - p.truth[0],
                p.estimate[1] - p.truth[1],
                p.estimate[2] - p.truth[2],
            );
            d.push((ex * ex + ey * ey + ez * ez).sqrt());
            h.push((ex * ex + ey * ey).sqrt());
            bx += ex;
            by += ey;
            bz += ez;
        }
        let nf = n as f64;
        assert_eq!(s.n, n);
        close(s.mean, d.iter().sum::<f64>() / nf, "mean");
        let mut sorted = d.clone();
        sorted.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let median = if n % 2 == 1 {
            sorted[n / 2]
        } else {
            0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
        };
        close(s.median, median, "median");
        close(
            s.rms,
            (d.iter().map(|x| x * x).sum::<f64>() / nf).sqrt(),
            "rms",
        );
        close(s.p75, quantile_1_based(&d, 0.75), "p75");
        close(s.p95, quantile_1_based(&d, 0.95), "p95");
        close(s.max, d.iter().cloned().fold(f64::MIN, f64::max), "max");
        close(s.bias[0], bx / nf, "bias x");
        close(s.bias[1], by / nf, "bias y");
        close(s.bias[2], bz / nf, "bias z");
        close(ev.ce95, quantile_1_based(&h, 0.95), "CE95");
        close(ev.se95, quantile_1_based(&d, 0.95), "SE95");
        // Inside the ellipsoid: by the explicit inverse.
        let inside = pairs
            .iter()
            .filter(|p| {
                let e = p.estimate - p.truth;
                (e.transpose() * p.covariance.unwrap().try_inverse().unwrap() * e)[0] <= CHI2_95_3D
            })
            .count();
        close(s.within_95.unwrap(), inside as f64 / nf, "within_95");
    }
}

#[test]
fn within_95_ellipsoid_is_honest_over_2000_emitters() {
    let right = evaluate_positions(&simulated(2000, 18, 1.0)).unwrap();
    let w = right.stats.within_95.unwrap();
    println!("within the 95 % ellipsoid: {w}");
    assert!((w - 0.95).abs() <= 0.03, "{w}");
    // A covariance too small by 1.5 in σ is caught.
    let wrong = evaluate_positions(&simulated(2000, 18, 1.5)).unwrap();
    let w = wrong.stats.within_95.unwrap();
    println!("with σ 1.5 × too small: {w}");
    assert!(w < 0.8, "{w}");
}

#[test]
fn angle_metrics_and_their_ellipse() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let pairs: Vec<AnglePair> = (0..2000)
        .map(|_| {
            let truth = Vector2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5));
            let (sx, sy, rho): (f64, f64, f64) = (
                rng.random_range(1e-4..1e-3),
                rng.random_range(1e-4..1e-3),
                rng.random_range(-0.8..0.8),
            );
            let c = Matrix2::new(sx * sx, rho * sx * sy, rho * sx * sy, sy * sy);
            let z = Vector2::new(
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            );
            AnglePair {
                truth,
                estimate: truth + c.cholesky().unwrap().l() * z,
                covariance: Some(c),
            }
        })
        .collect();
    let ev = evaluate_angles(&pairs).unwrap();
    let d: Vec<f64> = pairs
        .iter()
        .map(|p| {
            let (ex, ey) = (p.estimate.x - p.truth.x, p.estimate.y - p.truth.y);
            (ex * ex + ey * ey).sqrt()
        })
        .collect();
    close(
        ev.stats.rms,
        (d.iter().map(|x| x * x).sum::<f64>() / 2000.0).sqrt(),
        "rms",
    );
    close(ev.stats.p75, quantile_1_based(&d, 0.75), "p75");
    let w = ev.stats.within_95.unwrap();
    assert!((w - 0.95).abs() <= 0.03, "{w}");
}

#[test]
fn bad_inputs_are_typed_errors() {
    assert!(matches!(
        evaluate_positions(&[]),
        Err(LocateError::InvalidInput { .. })
    ));
    let mut pairs = simulated(3, 9, 1.0);
    pairs[1].covariance = Some(Matrix3::new(1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0));
    let e = evaluate_positions(&pairs).unwrap_err();
    assert!(
        e.to_string().contains("pair 1 is not positive definite"),
        "{e}"
    );
    pairs[1].estimate.x = f64::NAN;
    assert!(matches!(
        evaluate_positions(&pairs),
        Err(LocateError::NonFinite { .. })
    ));
    // Without covariances there is no honesty fraction.
    let mut pairs = simulated(3, 9, 1.0);
    pairs[0].covariance = None;
    assert_eq!(evaluate_positions(&pairs).unwrap().stats.within_95, None);
}

/// Definition 7 over the located sizes and `failures` copies of a finite
/// `penalty`, written independently of the library.
fn with_penalty(sizes: &[f64], failures: usize, penalty: f64, q: f64) -> f64 {
    let mut all = sizes.to_vec();
    all.extend(std::iter::repeat_n(penalty, failures));
    quantile_1_based(&all, q)
}

#[test]
fn failures_count_as_infinite_errors_in_the_percentiles() {
    // Closed form: sizes 1, 2, 3, 4 and one failure, N = 5: the median is
    // the 3rd value (3), the 75th percentile the 4th exactly (4), the 95th
    // interpolates towards the failure (infinite).
    let s = psdcal_locate::with_failures(&[4.0, 1.0, 3.0, 2.0], 1).unwrap();
    assert_eq!((s.attempted, s.failures), (5, 1));
    close(s.success_rate, 0.8, "success rate");
    assert_eq!((s.median, s.p75, s.p95), (Some(3.0), Some(4.0), None));
    assert!(psdcal_locate::with_failures(&[], 0).is_none());
    let all_failed = psdcal_locate::with_failures(&[], 3).unwrap();
    assert_eq!((all_failed.success_rate, all_failed.median), (0.0, None));
    // Seeded data against a huge finite penalty: a finite percentile equals
    // the penalised one; an infinite one is the one the penalty moves.
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut infinite_seen = 0;
    for _ in 0..200 {
        let n = rng.random_range(1..40);
        let k = rng.random_range(0..12);
        let sizes: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..50.0)).collect();
        let s = psdcal_locate::with_failures(&sizes, k).unwrap();
        close(s.success_rate, n as f64 / (n + k) as f64, "success rate");
        for (q, got) in [(0.5, s.median), (0.75, s.p75), (0.95, s.p95)] {
            let (a, b) = (
                with_penalty(&sizes, k, 1e9, q),
                with_penalty(&sizes, k, 1e12, q),
            );
            match got {
                Some(v) => {
                    close(v, a, "finite percentile");
                    close(v, b, "finite percentile");
                }
                None => {
                    infinite_seen += 1;
                    assert!(b > 1e3 * a.max(1.0) * 0.5 && b > 1e8, "{a} {b}");
                }
            }
        }
        if k == 0 {
            let mut sorted = sizes.clone();
            sorted.sort_by(f64::total_cmp);
            assert_eq!(s.p75, percentile(&sorted, 0.75));
        }
    }
    assert!(infinite_seen > 20, "{infinite_seen}");
}
