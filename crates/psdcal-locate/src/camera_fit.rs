//! A calibrated sensor as OpenCV's camera model: the rational model
//! ([`crate::opencv_model`]) fitted by least squares over the sensor's
//! valid region, and the conversion's error (docs/model.md §8.7).
//!
//! psdcal's model maps a measured point `m` to its ray `ρ(m) = (a, b)`
//! (docs/model.md §2–3, a PSD map first when the calibration has one);
//! OpenCV's maps a ray to an image point `P_θ(ρ)`. The fit samples `m` on
//! an `N × N` grid over the active area (edges included), keeps the points
//! inside the valid region (docs/model.md §8.2) and minimises
//!
//! ```text
//! Σ_m ‖P_θ(ρ(m)) − m‖²        (mm²)
//! ```
//!
//! over `fx, fy, cx, cy` and the distortion coefficients (psdcal-solver's
//! Levenberg–Marquardt; the start is the pinhole `f, cx, cy` without
//! distortion; the rational model starts from the 5-coefficient fit).
//!
//! The error is then measured on a finer grid (`M × M`, default 101, not
//! the fit's points): the **point error** `‖P_θ(ρ(m)) − m‖` (µm), and the
//! **angle error** per axis, `|atan x'_θ(m) − αx(m)|` and likewise for `y`,
//! with `(x'_θ, y'_θ)` the ray OpenCV's model gives the point `m`
//! (`P_θ⁻¹`, Newton's method) and `α` psdcal's angles of arrival. A point
//! the fitted model cannot invert is counted (`unanswered`): the model does
//! not represent the calibration there.

use nalgebra::Vector2;
use psdcal_model::Model;
use psdcal_solver::{solve, Problem, ResidualTerm, SolverOptions, Step, Termination};

use crate::calibrated_sensor::CalibratedSensor;
use crate::error::LocateError;
use crate::opencv_model::{OpenCv8, OPENCV8_LEN, RATIONAL_ONLY};

/// Which OpenCV model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OpenCvKind {
    /// `k1, k2, p1, p2, k3` (ROS's `plumb_bob`).
    Five,
    /// `k1, k2, p1, p2, k3, k4, k5, k6` (`CALIB_RATIONAL_MODEL`,
    /// `LENSMODEL_OPENCV8`, ROS's `rational_polynomial`).
    Rational,
}

/// Options of [`fit_opencv`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraFitOptions {
    /// Fit grid points per side.
    pub fit_grid: usize,
    /// Error grid points per side.
    pub check_grid: usize,
}

impl Default for CameraFitOptions {
    /// 41 × 41 fitted points, the error on 101 × 101.
    fn default() -> Self {
        Self {
            fit_grid: 41,
            check_grid: 101,
        }
    }
}

/// The fitted model and its error over the valid region.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraFit {
    /// Which model.
    pub kind: OpenCvKind,
    /// The fitted model (mm on the sensor).
    pub model: OpenCv8,
    /// Points fitted.
    pub fitted_points: usize,
    /// Points checked (the error grid's points inside the valid region).
    pub checked_points: usize,
    /// Checked points the model cannot invert (no ray).
    pub unanswered: usize,
    /// RMS point error, µm.
    pub rms_um: f64,
    /// Largest point error, µm.
    pub max_um: f64,
    /// RMS angle error over both axes, degrees.
    pub rms_deg: f64,
    /// Largest angle error of either axis, degrees (over the answered points).
    pub max_deg: f64,
    /// Where the largest angle error is (measured point, mm).
    pub worst_at_mm: Vector2<f64>,
    /// Why the solver stopped.
    pub termination: Termination,
}

/// Measured points of an `n × n` grid over the active area (edges
/// included) inside the sensor's valid region and its stages' domains,
/// with their rays.
fn samples(
    sensor: &CalibratedSensor,
    chain: &Model,
    n: usize,
) -> Vec<(Vector2<f64>, Vector2<f64>)> {
    let (lx, ly) = (sensor.geometry.lx, sensor.geometry.ly);
    let mut out = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let t = |k: usize| k as f64 / (n - 1) as f64 - 0.5;
            let m = Vector2::new(lx * t(i), ly * t(j));
            if sensor.check_valid_region(&m).is_err() || !chain.in_domain(&m) {
                continue;
            }
            let ray = chain.ray(&m);
            if ray.x.is_finite() && ray.y.is_finite() {
                out.push((m, ray));
            }
        }
    }
    out
}

/// The fit as a problem for psdcal-solver: the global block is the freed
/// parameters, one two-row residual per sample.
struct Fit<'a> {
    samples: &'a [(Vector2<f64>, Vector2<f64>)],
    free: Vec<usize>,
}

impl Problem for Fit<'_> {
    type State = OpenCv8;
    type Error = ();

    fn global_len(&self) -> usize {
        self.free.len()
    }

    fn block_count(&self) -> usize {
        0
    }

    fn evaluate(
        &self,
        state: &OpenCv8,
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>),
    ) -> Result<(), ()> {
        let mut a = vec![0.0; 2 * self.free.len()];
        for (m, ray) in self.samples {
            let p = state.project_with_jacobians(ray);
            let r = p.point - m;
            if !(r.x.is_finite() && r.y.is_finite()) {
                return Err(());
            }
            if jacobians {
                for (k, &c) in self.free.iter().enumerate() {
                    a[2 * k] = p.wrt_params[(0, c)];
                    a[2 * k + 1] = p.wrt_params[(1, c)];
                }
            }
            visit(&ResidualTerm {
                r: r.as_slice(),
                a: &a,
                block: None,
            });
        }
        Ok(())
    }

    fn apply_step(&self, state: &OpenCv8, step: &Step) -> Option<OpenCv8> {
        let mut next = *state;
        for (k, &c) in self.free.iter().enumerate() {
            next.params[c] += step.da[k];
        }
        next.params.iter().all(|v| v.is_finite()).then_some(next)
    }
}

fn solve_kind(
    samples: &[(Vector2<f64>, Vector2<f64>)],
    kind: OpenCvKind,
    start: OpenCv8,
) -> Result<(OpenCv8, Termination), LocateError> {
    let free: Vec<usize> = (0..OPENCV8_LEN)
        .filter(|c| kind == OpenCvKind::Rational || !RATIONAL_ONLY.contains(c))
        .collect();
    let problem = Fit { samples, free };
    let options = SolverOptions {
        max_iterations: 300,
        cost_tolerance: 1e-12,
        step_tolerance: 1e-12,
        ..SolverOptions::default()
    };
    let solution = solve(&problem, start, &options).map_err(|_| LocateError::InvalidInput {
        what: "camera model fit",
        reason: "the model overflows at the start".into(),
    })?;
    Ok((solution.state, solution.report.termination))
}

/// OpenCV's model of `kind` fitted to `sensor` over its valid region, with
/// the conversion's error (module docs).
pub fn fit_opencv(
    sensor: &CalibratedSensor,
    kind: OpenCvKind,
    options: &CameraFitOptions,
) -> Result<CameraFit, LocateError> {
    for (what, n) in [
        ("fit grid", options.fit_grid),
        ("check grid", options.check_grid),
    ] {
        if !(2..=crate::maps::MAX_GRID).contains(&n) {
            return Err(LocateError::InvalidInput {
                what,
                reason: format!(
                    "{n} points per side; expected 2 to {}",
                    crate::maps::MAX_GRID
                ),
            });
        }
    }
    let chain = sensor.chain();
    chain.validate()?;
    let fit_samples = samples(sensor, &chain, options.fit_grid);
    if fit_samples.len() < 2 * OPENCV8_LEN {
        return Err(LocateError::InvalidInput {
            what: "valid region",
            reason: format!(
                "only {} of the {}×{} grid points over the active area are inside it; \
                 too few to fit a camera model",
                fit_samples.len(),
                options.fit_grid,
                options.fit_grid
            ),
        });
    }
    let m = &sensor.model;
    let i = &m.intrinsics;
    let start = OpenCv8::pinhole(i.f, i.cx, i.cy);
    let (five, mut termination) = solve_kind(&fit_samples, OpenCvKind::Five, start)?;
    let model = if kind == OpenCvKind::Rational {
        let (rational, t) = solve_kind(&fit_samples, OpenCvKind::Rational, five)?;
        termination = t;
        rational
    } else {
        five
    };
    let mut fit = CameraFit {
        kind,
        model,
        fitted_points: fit_samples.len(),
        checked_points: 0,
        unanswered: 0,
        rms_um: 0.0,
        max_um: 0.0,
        rms_deg: 0.0,
        max_deg: 0.0,
        worst_at_mm: Vector2::zeros(),
        termination,
    };
    let (mut sum_um, mut sum_deg, mut answered) = (0.0, 0.0, 0usize);
    for (point, ray) in samples(sensor, &chain, options.check_grid) {
        fit.checked_points += 1;
        let e_um = (model.project(&ray) - point).norm() * 1e3;
        sum_um += e_um * e_um;
        fit.max_um = fit.max_um.max(e_um);
        let Some(back) = model.unproject(&point, &ray) else {
            fit.unanswered += 1;
            continue;
        };
        answered += 1;
        let ex = (back.x.atan() - ray.x.atan()).abs().to_degrees();
        let ey = (back.y.atan() - ray.y.atan()).abs().to_degrees();
        sum_deg += ex * ex + ey * ey;
        if ex.max(ey) > fit.max_deg {
            fit.max_deg = ex.max(ey);
            fit.worst_at_mm = point;
        }
    }
    fit.rms_um = (sum_um / fit.checked_points.max(1) as f64).sqrt();
    fit.rms_deg = (sum_deg / (2 * answered.max(1)) as f64).sqrt();
    Ok(fit)
}
