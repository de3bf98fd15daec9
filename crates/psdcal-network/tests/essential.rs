//! The relative pose from rays, against a pose chosen here: points in
//! front of two sensors, their unit rays, a few gross outliers.

use nalgebra::Vector3;
use psdcal_model::Pose;
use psdcal_network::essential::{eight_point, epipolar_error, relative_pose};
use psdcal_network::geometry::{kabsch, meet_rays, rotation_between};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn scene(j_from_i: &Pose, n: usize, rng: &mut ChaCha8Rng) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let mut pairs = Vec::new();
    while pairs.len() < n {
        let p = Vector3::new(
            rng.random_range(-2000.0..2000.0),
            rng.random_range(-2000.0..2000.0),
            rng.random_range(1500.0..5000.0),
        );
        let q = j_from_i.transform(&p);
        if q.z > 100.0 {
            pairs.push((p.normalize(), q.normalize()));
        }
    }
    pairs
}

#[test]
fn the_relative_pose_is_recovered_up_to_scale_despite_outliers() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    // A wide-angle pair: 70° apart, facing a common volume.
    let j_from_i = Pose::new(
        Vector3::new(0.1, -1.2, 0.2),
        Vector3::new(2500.0, 300.0, 1200.0),
    );
    let mut pairs = scene(&j_from_i, 400, &mut rng);
    for k in (0..400).step_by(25) {
        pairs[k].1 = Vector3::new(rng.random(), rng.random(), 1.0).normalize();
    }
    let rel = relative_pose(&pairs, 1e-3, 200, &mut rng).unwrap();
    let r_err = rel.j_from_i.rotation() * j_from_i.rotation().transpose();
    let angle = ((r_err.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos();
    assert!(angle < 1e-9, "rotation off by {angle} rad");
    let t_dir = j_from_i.t.normalize();
    assert!(
        (rel.j_from_i.t - t_dir).norm() < 1e-9,
        "{:?} vs {:?}",
        rel.j_from_i.t,
        t_dir
    );
    let outliers = rel.inliers.iter().filter(|f| !**f).count();
    assert_eq!(outliers, 16);
}

#[test]
fn the_eight_point_matrix_satisfies_every_constraint_of_exact_rays() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let j_from_i = Pose::new(
        Vector3::new(0.3, 0.2, -0.1),
        Vector3::new(-800.0, 100.0, 50.0),
    );
    let pairs = scene(&j_from_i, 8, &mut rng);
    let e = eight_point(&pairs).unwrap();
    // [t]× R up to scale and sign.
    let t = j_from_i.t.normalize();
    let tx = nalgebra::Matrix3::new(0.0, -t.z, t.y, t.z, 0.0, -t.x, -t.y, t.x, 0.0);
    let truth = tx * j_from_i.rotation();
    let s = truth.norm() / e.norm();
    let d = (e * s - truth).norm().min((e * s + truth).norm());
    assert!(d < 1e-8, "{d}");
    for (xi, xj) in scene(&j_from_i, 20, &mut rng) {
        assert!(epipolar_error(&e, &xi, &xj) < 1e-10);
    }
}

#[test]
fn rays_meet_where_they_were_cast_and_kabsch_undoes_a_pose() {
    let target = Vector3::new(100.0, -200.0, 3000.0);
    let origins = [
        Vector3::zeros(),
        Vector3::new(1000.0, 0.0, 0.0),
        Vector3::new(0.0, 800.0, 200.0),
    ];
    let rays: Vec<_> = origins
        .iter()
        .map(|c| (*c, (target - c).normalize()))
        .collect();
    assert!((meet_rays(&rays).unwrap() - target).norm() < 1e-9);
    assert!(meet_rays(&rays[..1]).is_none());
    let pose = Pose::new(Vector3::new(0.4, -0.3, 1.1), Vector3::new(10.0, 20.0, 30.0));
    let pts = [
        Vector3::zeros(),
        Vector3::new(500.0, 0.0, 0.0),
        Vector3::new(200.0, 150.0, 0.0),
    ];
    let pairs: Vec<_> = pts.iter().map(|p| (*p, pose.transform(p))).collect();
    let fit = kabsch(&pairs).unwrap();
    assert!((fit.rotation() - pose.rotation()).norm() < 1e-12);
    assert!((fit.t - pose.t).norm() < 1e-9);
    let (a, b) = (Vector3::new(1.0, 2.0, 3.0), Vector3::new(-3.0, 0.5, 1.0));
    assert!((rotation_between(&a, &b).unwrap() * a.normalize() - b.normalize()).norm() < 1e-12);
    assert!((rotation_between(&a, &-a).unwrap() * a + a).norm() < 1e-12);
}
