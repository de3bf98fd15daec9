//! The start's objective and what is computed from it (the steps 5–6 of
//! [`initialize`](fn@crate::initialize); docs/model.md §4.5):
//!
//! ```text
//! J(f, cx, cy) = min over k1 and the poses of
//!                Σ_images Σ_points ‖back_project(model, pose_i, m_ij) − P_j‖²   (mm²)
//! ```
//!
//! the template-plane error of (P29) on the measured points at fixed
//! intrinsics, `k2` held at the preliminary estimate, the poses starting from
//! the homographies ((P26)–(P28)) and `k1` from the preliminary estimate,
//! minimised by the one solver (one shared parameter: the Schur complement
//! leaves a scalar). From it: the focal search (a log-spaced grid, then a
//! golden-section search in `ln f`), and the refined closed form (`f, cx, cy,
//! k1, k2` and the poses freed; on large sets descended first on
//! [`crate::initialize::REFINE_SUBSET_IMAGES`] images spread over the set).

use psdcal_model::{Model, Pose, SensorModel};
use psdcal_solver::{solver, SolverOptions};

use crate::problem::calibration_problem::{CalibrationProblem, FitState};
use crate::start::homography::{fast_homography, Homography};
use crate::start::zhang::pose_from_homography;
use crate::{CalibError, CalibrationData, ImageObservations};
use psdcal_model::CostKind;

/// Most images the refined closed form descends on before the whole set
/// (`focal_profile::Problem::refined`).
pub const REFINE_SUBSET_IMAGES: usize = 4;

/// What the focal search did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FocalSearchReport {
    /// Best focal length, mm.
    pub f: f64,
    /// Centre used, mm.
    pub cx: f64,
    /// Centre used, mm.
    pub cy: f64,
    /// `J` at the best `f`, mm².
    pub cost: f64,
    /// Searched interval, mm.
    pub range: [f64; 2],
    /// Grid points per centre.
    pub grid_points: usize,
    /// Golden-section iterations (winning centre).
    pub golden_iterations: usize,
    /// Evaluations of `J`, all centres.
    pub evaluations: usize,
    /// The best grid point was an end of the range (the optimum may lie
    /// outside it).
    pub at_boundary: bool,
    /// The winning centre came from the closed form (otherwise `(0, 0)`).
    pub centre_from_closed_form: bool,
}

/// Initial damping of the whole set's refinement from the subset's
/// minimum: the start is close, and damping the strongly correlated
/// directions (f with the depths) would cost an iteration for each factor 3
/// that it decays by.
const NEAR_LAMBDA: f64 = 1e-6;

/// Starting damping of the closed form's refinement. Measured on 18 sets
/// (lenses 1 and 2; 9, 12 and 20 images; 3 seeds; 40 dB): against 1e-3, the
/// whole `calibrate` process executes 3–14 % fewer instructions, and the
/// final answers agree within 2e-7 σ.
const REFINED_LAMBDA: f64 = 1e-7;

/// Solver iterations of one precise evaluation of `J`.
const PROFILE_ITERATIONS: usize = 40;
/// Solver iterations and relative cost tolerance of a coarse evaluation of
/// `J` (the basin check's comparisons with a factor-two margin).
const COARSE_ITERATIONS: usize = 10;
const COARSE_TOLERANCE: f64 = 1e-4;
/// Solver iterations of the refined closed form.
const REFINED_ITERATIONS: usize = 100;
/// Width in `ln f` at which the golden-section search stops (0.1 % in `f`;
/// the refinement that follows settles `f`).
const GOLDEN_TOLERANCE: f64 = 1e-3;

/// Everything `J` is computed from: the data (or a subset of its images),
/// their homographies and the preliminary distortion.
pub(crate) struct Problem {
    pub(crate) data: CalibrationData,
    pub(crate) homographies: Vec<Homography>,
    pub(crate) k1_start: f64,
    pub(crate) k2: f64,
    /// Rounding floor of cost comparisons, mm².
    pub(crate) floor: f64,
}

/// `J` (or a refined start) and its minimiser.
pub(crate) struct Profile {
    pub(crate) cost: f64,
    pub(crate) model: SensorModel,
    pub(crate) poses: Vec<Pose>,
    pub(crate) converged: bool,
}

/// How precisely a profile value is needed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Precision {
    /// To compare values a factor two apart (the basin check, which the
    /// search backs up).
    Coarse,
    /// The start handed on.
    Fine,
}

impl Problem {
    /// The start at `(f, cx, cy)`: the preliminary `k1, k2` and the poses of
    /// the homographies (`k1 = 0` when the preliminary one folds a point).
    pub(crate) fn plain_start(&self, f: f64, cx: f64, cy: f64) -> Result<Profile, CalibError> {
        let mut model = SensorModel::pinhole(f, cx, cy);
        model.distortion.k1 = self.k1_start;
        model.distortion.k2 = self.k2;
        let poses = self
            .homographies
            .iter()
            .map(|h| pose_from_homography(h, f, cx, cy))
            .collect::<Result<Vec<_>, _>>()?;
        let mut cost = self.sum_squares(&model, &poses);
        if !cost.is_finite() {
            // The distortion start may fold the points; retry without it.
            model.distortion.k1 = 0.0;
            cost = self.sum_squares(&model, &poses);
        }
        Ok(Profile {
            cost,
            model,
            poses,
            converged: false,
        })
    }

    pub(crate) fn sum_squares(&self, model: &SensorModel, poses: &[Pose]) -> f64 {
        crate::problem::calibration_problem::total_cost(
            &self.data,
            CostKind::Template,
            None,
            &model.into(),
            poses,
        )
        .ok()
        .filter(|c| c.is_finite())
        .unwrap_or(f64::INFINITY)
    }

    /// Minimises the template-plane error over the `free` parameters and
    /// every pose from the plain start at `(f, cx, cy)`, with the one solver.
    pub(crate) fn minimise(
        &self,
        f: f64,
        cx: f64,
        cy: f64,
        free: &[&str],
        settings: &SolverOptions,
    ) -> Result<Profile, CalibError> {
        let start = self.plain_start(f, cx, cy)?;
        if !start.cost.is_finite() {
            return Err(CalibError::Numerical {
                stage: "initialisation",
                reason: format!("a template point does not back-project at f = {f:.4} mm"),
            });
        }
        self.minimise_from(&start.model, start.poses, free, settings)
    }

    /// Minimises the template-plane error over the `free` parameters and
    /// every pose from `model` and `poses`.
    pub(crate) fn minimise_from(
        &self,
        model: &SensorModel,
        poses: Vec<Pose>,
        free: &[&str],
        settings: &SolverOptions,
    ) -> Result<Profile, CalibError> {
        let names: Vec<String> = free.iter().map(|n| n.to_string()).collect();
        let model = Model::standard(model);
        let problem =
            CalibrationProblem::new(&self.data, CostKind::Template, &model, &names, None)?;
        let state = FitState { model, poses };
        let solution = solver::solve(&problem, state, settings)?;
        Ok(Profile {
            cost: solution.cost,
            model: solution.state.model.sensor_model(),
            poses: solution.state.poses,
            converged: solution.report.termination.converged(),
        })
    }

    /// `J(f, cx, cy)`: the minimum over `k1` and the poses.
    pub(crate) fn profile(
        &self,
        f: f64,
        cx: f64,
        cy: f64,
        precision: Precision,
    ) -> Result<Profile, CalibError> {
        let (cost_tolerance, max_iterations) = match precision {
            Precision::Coarse => (COARSE_TOLERANCE, COARSE_ITERATIONS),
            Precision::Fine => (1e-10, PROFILE_ITERATIONS),
        };
        let settings = SolverOptions {
            max_iterations,
            cost_tolerance,
            step_tolerance: 1e-10,
            initial_lambda: 1e-4,
            exact_cost: 1e-3 * self.floor,
            step_floor: 1e-3 * self.floor,
            robust: None,
        };
        self.minimise(f, cx, cy, &["k1"], &settings)
    }

    /// The closed form refined: `f, cx, cy, k1, k2` (the parameters the start
    /// provides) and the poses, from the plain start at `(f, cx, cy)`. On
    /// sets larger than [`REFINE_SUBSET_IMAGES`] and a half, the long descent
    /// from the closed form runs on that many images spread over the set, and
    /// the whole set starts from its intrinsics (its own poses for its
    /// images, the homographies' at the new intrinsics for the others): the
    /// same minimum, at a fraction of the linearisations of the whole set.
    pub(crate) fn refined(&self, f: f64, cx: f64, cy: f64) -> Result<Profile, CalibError> {
        const FREE: [&str; 5] = ["f", "cx", "cy", "k1", "k2"];
        let settings = SolverOptions {
            max_iterations: REFINED_ITERATIONS,
            cost_tolerance: 1e-6,
            step_tolerance: 1e-8,
            initial_lambda: REFINED_LAMBDA,
            exact_cost: 1e-3 * self.floor,
            step_floor: 1e-3 * self.floor,
            robust: None,
        };
        let n = self.data.images.len();
        let sub = REFINE_SUBSET_IMAGES;
        if 2 * n <= 3 * sub {
            return self.minimise(f, cx, cy, &FREE, &settings);
        }
        let subset = self.subset(sub);
        let rough = match subset.minimise(f, cx, cy, &FREE, &settings) {
            Ok(p) if p.converged && p.cost.is_finite() => p,
            _ => return self.minimise(f, cx, cy, &FREE, &settings),
        };
        let mut poses = match self.poses_at(&rough.model) {
            Ok(p) => p,
            Err(_) => return self.minimise(f, cx, cy, &FREE, &settings),
        };
        for (i, pose) in spread(n, sub).into_iter().zip(rough.poses) {
            poses[i] = pose;
        }
        if !self.sum_squares(&rough.model, &poses).is_finite() {
            return self.minimise(f, cx, cy, &FREE, &settings);
        }
        let near = SolverOptions {
            initial_lambda: NEAR_LAMBDA,
            ..settings
        };
        self.minimise_from(&rough.model, poses, &FREE, &near)
    }

    /// One pose per image for a known `model`: the homography of the
    /// image's ideal points (the model's correction of the measured points)
    /// and the pose it gives at the model's intrinsics (P26)–(P28).
    pub(crate) fn poses_at(&self, model: &SensorModel) -> Result<Vec<Pose>, CalibError> {
        let chain = Model::standard(model);
        let k = &model.intrinsics;
        self.data
            .images
            .iter()
            .map(|im| {
                let template: Vec<_> = im
                    .points
                    .iter()
                    .map(|o| self.data.template[o.led])
                    .collect();
                let ideal: Vec<_> = im.points.iter().map(|o| chain.ideal(&o.measured)).collect();
                let h = fast_homography(&template, &ideal)?;
                pose_from_homography(&h, k.f, k.cx, k.cy)
            })
            .collect()
    }

    /// The same problem on at most `max_images` images spread evenly over
    /// the set (all of them when there are no more).
    pub(crate) fn subset(&self, max_images: usize) -> Problem {
        let n = self.data.images.len();
        let keep = spread(n, max_images);
        let scale = keep.len() as f64 / n as f64;
        Problem {
            data: subset_images(&self.data, max_images, &|_| true),
            homographies: keep.iter().map(|&i| self.homographies[i]).collect(),
            k1_start: self.k1_start,
            k2: self.k2,
            floor: self.floor * scale,
        }
    }

    pub(crate) fn cost_or_inf(&self, f: f64, cx: f64, cy: f64, precision: Precision) -> f64 {
        self.profile(f, cx, cy, precision)
            .map(|p| p.cost)
            .unwrap_or(f64::INFINITY)
    }

    /// Grid and golden-section search over `ln f` in `[lo, hi]`.
    pub(crate) fn search(
        &self,
        lo: f64,
        hi: f64,
        n: usize,
        cx: f64,
        cy: f64,
    ) -> Option<FocalSearchReport> {
        let (a, b) = (lo.ln(), hi.ln());
        let grid: Vec<f64> = (0..n)
            .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
            .collect();
        let costs: Vec<f64> = grid
            .iter()
            .map(|&l| self.cost_or_inf(l.exp(), cx, cy, Precision::Fine))
            .collect();
        let best = (0..n)
            .filter(|&i| costs[i].is_finite())
            .min_by(|&i, &j| costs[i].total_cmp(&costs[j]))?;
        let (mut x0, mut x3) = (grid[best.saturating_sub(1)], grid[(best + 1).min(n - 1)]);
        let phi = 0.5 * (5f64.sqrt() - 1.0);
        let mut x1 = x3 - phi * (x3 - x0);
        let mut x2 = x0 + phi * (x3 - x0);
        let mut c1 = self.cost_or_inf(x1.exp(), cx, cy, Precision::Fine);
        let mut c2 = self.cost_or_inf(x2.exp(), cx, cy, Precision::Fine);
        let mut iterations = 0;
        while x3 - x0 > GOLDEN_TOLERANCE && iterations < 100 {
            iterations += 1;
            if c1 <= c2 {
                (x3, x2, c2) = (x2, x1, c1);
                x1 = x3 - phi * (x3 - x0);
                c1 = self.cost_or_inf(x1.exp(), cx, cy, Precision::Fine);
            } else {
                (x0, x1, c1) = (x1, x2, c2);
                x2 = x0 + phi * (x3 - x0);
                c2 = self.cost_or_inf(x2.exp(), cx, cy, Precision::Fine);
            }
        }
        let (mut lf, mut cost) = if c1 <= c2 { (x1, c1) } else { (x2, c2) };
        if cost.is_nan() || cost > costs[best] {
            (lf, cost) = (grid[best], costs[best]);
        }
        Some(FocalSearchReport {
            f: lf.exp(),
            cx,
            cy,
            cost,
            range: [lo, hi],
            grid_points: n,
            golden_iterations: iterations,
            evaluations: n + 2 + iterations,
            at_boundary: best == 0 || best == n - 1,
            centre_from_closed_form: false,
        })
    }
}

/// At most `max` of `n` indices, spread evenly (all of them when `n ≤ max`).
pub(crate) fn spread(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        (0..n).collect()
    } else {
        (0..max).map(|k| k * n / max).collect()
    }
}

/// The data set restricted to at most `max` of its `eligible` images,
/// spread over them (without amplitudes: the start works on the measured
/// points). Only the kept images are copied.
pub(crate) fn subset_images(
    data: &CalibrationData,
    max: usize,
    eligible: &dyn Fn(&ImageObservations) -> bool,
) -> CalibrationData {
    let pool: Vec<&ImageObservations> = data.images.iter().filter(|im| eligible(im)).collect();
    CalibrationData {
        template: data.template.clone(),
        lines: data.lines.clone(),
        images: spread(pool.len(), max)
            .into_iter()
            .map(|i| pool[i].clone())
            .collect(),
        geometry: data.geometry,
        amplitudes: None,
        noise_scale: None,
    }
}
