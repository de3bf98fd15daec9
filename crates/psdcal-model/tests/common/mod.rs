//! Shared machinery of the model test suite: example parameter sets and a
//! Jacobian checker against central finite differences.
#![allow(dead_code)]

use nalgebra::{DMatrix, DVector, Vector2, Vector3};
use psdcal_model::{Pose, SensorModel};

/// Example sensors every map is checked on: the paper's two lenses, lens 2
/// with PSD distortion, and a model with every parameter non-zero.
pub fn example_models() -> Vec<(&'static str, SensorModel)> {
    let lens1 = SensorModel::paper_lens1();
    let lens2 = SensorModel::paper_lens2();
    let mut lens1_psd = lens1;
    lens1_psd.distortion.l1 = SensorModel::PAPER_L1;
    let mut lens2_psd = lens2;
    lens2_psd.distortion.l1 = SensorModel::PAPER_L1;
    let mut full = lens2;
    full.intrinsics.skew = 0.03;
    full.distortion.k3 = -2e-7;
    full.distortion.p1 = 4e-4;
    full.distortion.p2 = -3e-4;
    full.distortion.l1 = SensorModel::PAPER_L1;
    full.distortion.l2 = 2e-6;
    vec![
        ("lens1", lens1),
        ("lens2", lens2),
        ("lens1+l1", lens1_psd),
        ("lens2+l1", lens2_psd),
        ("full", full),
    ]
}

/// Example template poses `sensor_from_template`: 0.7–1.5 m away, tilted up
/// to ~30°, including an exactly fronto-parallel one (rvec = 0).
pub fn example_poses() -> Vec<Pose> {
    vec![
        Pose::new(Vector3::zeros(), Vector3::new(10.0, -20.0, 900.0)),
        Pose::new(
            Vector3::new(0.3, -0.2, 0.1),
            Vector3::new(-150.0, 80.0, 700.0),
        ),
        Pose::new(
            Vector3::new(-0.45, 0.25, -0.6),
            Vector3::new(120.0, 140.0, 1500.0),
        ),
        Pose::new(
            Vector3::new(1e-9, -2e-9, 5e-10),
            Vector3::new(0.0, 0.0, 1100.0),
        ),
        Pose::new(
            Vector3::new(0.1, 0.5, 2.8),
            Vector3::new(60.0, -90.0, 1200.0),
        ),
    ]
}

/// Template points (mm) used with [`example_poses`]: the centre and four
/// LEDs of `scatter14` (corners of the template).
pub fn example_template_points() -> Vec<Vector2<f64>> {
    vec![Vector2::new(0.0, 0.0), led(0), led(7), led(12), led(13)]
}

/// Typical magnitudes of the model parameters in [`psdcal_model::Param::ALL`]
/// order: finite-difference steps and tolerances are taken in these units.
pub const MODEL_SCALES: [f64; 11] = [
    10.0, 1.0, 1.0, 0.1, 1e-2, 1e-4, 1e-6, 1e-3, 1e-3, 1e-3, 1e-5,
];
/// Typical magnitudes of the pose parameters (rad, rad, rad, mm, mm, mm).
pub const POSE_SCALES: [f64; 6] = [1.0, 1.0, 1.0, 1000.0, 1000.0, 1000.0];

/// Checks an analytic Jacobian against central finite differences.
///
/// `f` maps an input vector to an output vector; `analytic` is its Jacobian
/// at `x`; `scales` are the inputs' typical magnitudes. The check runs in
/// scaled inputs `u_j = x_j / scale_j`, with a step of 1e-5 in `u`, where
/// every column has a comparable size. A column passes when
/// `‖a − fd‖ ≤ rel_tol · ‖fd‖ + 1e-8 · max_k ‖a_k‖` (all in scaled units): the
/// relative test on its own size, plus a floor well above the rounding of a
/// central difference (ε · internal magnitude / step ≈ 1e-10 of the largest
/// column here), so that an analytically zero column must have a vanishing
/// finite difference.
pub fn check_jacobian(
    name: &str,
    x: &DVector<f64>,
    scales: &[f64],
    f: &dyn Fn(&DVector<f64>) -> DVector<f64>,
    analytic: &DMatrix<f64>,
    rel_tol: f64,
) {
    check_jacobian_with_floor(name, x, scales, f, analytic, rel_tol, 0.0)
}

/// [`check_jacobian`] with an absolute floor `abs_tol` (scaled units) added
/// to each column's tolerance: for columns that vanish at a point (a radial
/// term at the centre), where a central difference is rounding alone.
pub fn check_jacobian_with_floor(
    name: &str,
    x: &DVector<f64>,
    scales: &[f64],
    f: &dyn Fn(&DVector<f64>) -> DVector<f64>,
    analytic: &DMatrix<f64>,
    rel_tol: f64,
    abs_tol: f64,
) {
    let y0 = f(x);
    assert_eq!(analytic.nrows(), y0.len(), "{name}: Jacobian rows");
    assert_eq!(analytic.ncols(), x.len(), "{name}: Jacobian columns");
    assert_eq!(scales.len(), x.len(), "{name}: scales");
    let scaled = DMatrix::from_fn(analytic.nrows(), analytic.ncols(), |i, j| {
        analytic[(i, j)] * scales[j]
    });
    let largest = (0..x.len())
        .map(|j| scaled.column(j).norm())
        .fold(0.0, f64::max);
    for j in 0..x.len() {
        let col = scaled.column(j);
        let h = 1e-5 * scales[j];
        let mut xp = x.clone();
        xp[j] += h;
        let mut xm = x.clone();
        xm[j] -= h;
        let fd = (f(&xp) - f(&xm)) / (2.0 * h) * scales[j];
        let err = (col - &fd).norm();
        assert!(
            err <= rel_tol * fd.norm() + 1e-8 * largest + abs_tol,
            "{name}: column {j} analytic {:?} vs finite difference {:?} (scaled by {}; error {err:.3e})",
            col.as_slice(),
            fd.as_slice(),
            scales[j]
        );
    }
}

/// LED `k` of `scatter14` (psdcal_model::paper_setup), mm.
fn led(k: usize) -> Vector2<f64> {
    let (x, y) = psdcal_model::paper_setup::SCATTER14_MM[k];
    Vector2::new(x, y)
}
