//! Preliminary distortion correction (docs/model.md §4.1, the paper's Section 3.2
//! and (P30)): a rough radial correction estimated before the linear stage,
//! which is very sensitive to distortion.
//!
//! The correction has the form of the lens radial term of docs/model.md §2 with
//! the centre `c` held fixed (the sensor centre `(0, 0)` by default):
//!
//! ```text
//! d = m − c,   ρ = ‖d‖² / R²,   p = c + d (1 + u1 ρ + u2 ρ²),
//! k1 = u1 / R²,   k2 = u2 / R⁴
//! ```
//!
//! where `m` is a measured point, `p` the corrected one, and `R` the largest
//! distance of a measured point from `c` (the solver works in the
//! dimensionless `u1, u2`, each of which moves the outermost point by
//! `u·R`). A candidate must keep the correction monotone over the data,
//! `1 + 3 k1 r² + 5 k2 r⁴ > 0.1` for `r ≤ R` (no fold-over).
//!
//! Two costs, both scale-free, so that a correction that merely shrinks the
//! points cannot win:
//!
//! - *Line straightness* ([`crate::straightness`]; the paper's choice, in the
//!   Devernay–Faugeras form instead of the slopes of (P30)–(P35)): for every
//!   declared line seen with ≥ 3 LEDs in an image, the orthogonal distances of
//!   the corrected points to their total-least-squares line, divided by the
//!   square root of the scatter along the line, `e_j = n·(p_j − p̄)/√λ_max`;
//!   the sum of squares per line is `λ_min/λ_max` of its scatter matrix.
//! - *Homography consistency* (any template): for every image with ≥ 5
//!   points, the transfer residuals `H P_j − p_j` of the normalised-DLT
//!   homography of the corrected points, measured in the image's Hartley
//!   coordinates (multiplied by `√2 / mean distance to the centroid`).
//!
//! Both are minimised by a two-parameter Levenberg–Marquardt from `k = 0`
//! (analytic Jacobian for straightness, central differences for homography
//! consistency).

use nalgebra::{DVector, Matrix3, Vector2};
use psdcal_solver::{solver, Problem, ResidualTerm, SolverOptions, Step, Termination};

use crate::start::correction_cost::TwoParameterCost;
use crate::start::homography::{fast_homography_normalised, normalizing_transform};
use crate::{CalibError, CalibrationData};

/// Which preliminary correction to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preliminary {
    /// No correction (`k1 = k2 = 0`).
    Off,
    /// Line straightness; needs declared lines.
    Straightness,
    /// Homography consistency; any template.
    #[serde(rename = "homography")]
    HomographyConsistency,
    /// Straightness when the template declares usable lines, homography
    /// consistency otherwise. A report never carries `Auto`.
    #[default]
    Auto,
}

impl Preliminary {
    /// Every method, in the order the command line lists them.
    pub const ALL: [Preliminary; 4] = [
        Preliminary::Auto,
        Preliminary::Straightness,
        Preliminary::HomographyConsistency,
        Preliminary::Off,
    ];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Preliminary::Auto => "auto",
            Preliminary::Straightness => "straightness",
            Preliminary::HomographyConsistency => "homography",
            Preliminary::Off => "off",
        }
    }
}

impl std::str::FromStr for Preliminary {
    type Err = String;

    /// `auto`, `straightness`, `homography` or `off` (any case).
    fn from_str(text: &str) -> Result<Self, String> {
        let wanted = text.trim().to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|p| p.name() == wanted)
            .ok_or_else(|| {
                format!("expected auto, straightness, homography or off, found '{text}'")
            })
    }
}

#[cfg(feature = "clap")]
impl clap::ValueEnum for Preliminary {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

/// Options of [`estimate_preliminary`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreliminaryOptions {
    /// The method.
    pub method: Preliminary,
    /// The fixed centre of the correction, mm (default `(0, 0)`, the sensor
    /// centre).
    pub centre: Vector2<f64>,
    /// Levenberg–Marquardt iteration budget (default 50).
    pub max_iterations: usize,
}

impl Default for PreliminaryOptions {
    fn default() -> Self {
        Self {
            method: Preliminary::Auto,
            centre: Vector2::zeros(),
            max_iterations: 50,
        }
    }
}

/// Why the two-parameter solver stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PreliminaryTermination {
    /// The method was `Off`: nothing to do.
    NotRun,
    /// The cost (or the step) stopped changing.
    Converged,
    /// The damping grew without finding a better point.
    Stalled,
    /// The iteration budget ran out.
    MaxIterations,
}

/// What the preliminary correction did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreliminaryReport {
    /// The method actually run (never `Auto`).
    pub method: Preliminary,
    /// Estimated `k1`, mm⁻².
    pub k1: f64,
    /// Estimated `k2`, mm⁻⁴.
    pub k2: f64,
    /// The fixed centre, mm.
    pub centre: Vector2<f64>,
    /// Cost at `k = 0` (dimensionless, see the module documentation).
    pub cost_before: f64,
    /// Cost at the estimate.
    pub cost_after: f64,
    /// Accepted Levenberg–Marquardt iterations.
    pub iterations: usize,
    /// Cost evaluations.
    pub evaluations: usize,
    /// Terms of the cost: lines (straightness) or images (consistency).
    pub terms: usize,
    /// Why the solver stopped.
    pub termination: PreliminaryTermination,
}

impl PreliminaryReport {
    /// The report of no correction.
    pub fn off(centre: Vector2<f64>) -> Self {
        Self {
            method: Preliminary::Off,
            k1: 0.0,
            k2: 0.0,
            centre,
            cost_before: 0.0,
            cost_after: 0.0,
            iterations: 0,
            evaluations: 0,
            terms: 0,
            termination: PreliminaryTermination::NotRun,
        }
    }

    /// Applies the estimated correction to one measured point.
    pub fn correct(&self, measured: &Vector2<f64>) -> Vector2<f64> {
        radial_correct(measured, &self.centre, self.k1, self.k2)
    }

    /// The corrected points of every image, in the order of
    /// `data.images[i].points`.
    pub fn correct_data(&self, data: &CalibrationData) -> Vec<Vec<Vector2<f64>>> {
        data.images
            .iter()
            .map(|im| {
                im.points
                    .iter()
                    .map(|o| self.correct(&o.measured))
                    .collect()
            })
            .collect()
    }
}

/// `c + (m − c)(1 + k1 r² + k2 r⁴)`, `r = ‖m − c‖`.
pub fn radial_correct(
    measured: &Vector2<f64>,
    centre: &Vector2<f64>,
    k1: f64,
    k2: f64,
) -> Vector2<f64> {
    let d = measured - centre;
    let r2 = d.norm_squared();
    centre + d * (1.0 + r2 * (k1 + r2 * k2))
}

/// Checks the data for what every routine relies on ([`CalibrationData::check`]).
pub fn check_data(data: &CalibrationData) -> Result<(), CalibError> {
    data.check()
}

/// Whether `1 + 3 u1 s + 5 u2 s² > 0.1` for `s ∈ [0, 1]` (monotone correction
/// over the data's radius).
pub(crate) fn is_monotone(u: [f64; 2]) -> bool {
    let g = |s: f64| 1.0 + 3.0 * u[0] * s + 5.0 * u[1] * s * s;
    let mut ok = g(1.0) > 0.1 && u.iter().all(|v| v.is_finite());
    if u[1] > 0.0 {
        let s = -3.0 * u[0] / (10.0 * u[1]);
        if s > 0.0 && s < 1.0 {
            ok &= g(s) > 0.1;
        }
    }
    ok
}

/// Outcome of [`minimise`].
pub(crate) struct Minimum {
    pub u: [f64; 2],
    pub cost_before: f64,
    pub cost_after: f64,
    pub iterations: usize,
    pub evaluations: usize,
    pub termination: PreliminaryTermination,
}

/// A [`TwoParameterCost`] as a problem for the one solver: two global
/// parameters, no blocks, one-row residuals; steps that make the correction
/// non-monotone over the data are rejected.
struct TwoParameterProblem<'a> {
    cost: &'a dyn TwoParameterCost,
    evaluations: std::cell::Cell<usize>,
}

impl Problem for TwoParameterProblem<'_> {
    type State = [f64; 2];
    type Error = CalibError;

    fn global_len(&self) -> usize {
        2
    }

    fn block_count(&self) -> usize {
        0
    }

    fn evaluate(
        &self,
        u: &[f64; 2],
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>),
    ) -> Result<(), CalibError> {
        let r = self.cost.residuals(*u)?;
        self.evaluations.set(self.evaluations.get() + 1);
        if jacobians {
            let j = self.cost.jacobian(*u, &r)?;
            self.evaluations
                .set(self.evaluations.get() + self.cost.jacobian_evaluations());
            if j.iter().any(|v| !v.is_finite()) {
                return Err(CalibError::Numerical {
                    stage: "preliminary correction",
                    reason: "non-finite Jacobian".into(),
                });
            }
            for i in 0..r.len() {
                visit(&ResidualTerm {
                    r: &[r[i]],
                    a: &[j[(i, 0)], j[(i, 1)]],
                    block: None,
                });
            }
        } else {
            for v in r.iter() {
                visit(&ResidualTerm {
                    r: std::slice::from_ref(v),
                    a: &[],
                    block: None,
                });
            }
        }
        Ok(())
    }

    fn apply_step(&self, u: &[f64; 2], step: &Step) -> Option<[f64; 2]> {
        let trial = [u[0] + step.da[0], u[1] + step.da[1]];
        is_monotone(trial).then_some(trial)
    }
}

/// Levenberg–Marquardt from `u = 0` with the one solver.
pub(crate) fn minimise(
    cost: &dyn TwoParameterCost,
    max_iterations: usize,
) -> Result<Minimum, CalibError> {
    let problem = TwoParameterProblem {
        cost,
        evaluations: std::cell::Cell::new(0),
    };
    let settings = SolverOptions {
        // Accepted and rejected steps both count for the solver.
        max_iterations: 3 * max_iterations,
        // A rough correction (the refinement corrects it): a relative
        // decrease below 1e-6 ends it, one or two evaluations earlier than
        // 1e-10 (measured: 1.5 % of a whole calibration, the same answers).
        cost_tolerance: 1e-6,
        step_tolerance: 1e-12,
        initial_lambda: 1e-3,
        exact_cost: 1e-30,
        step_floor: 0.0,
        robust: None,
    };
    let solution = solver::solve(&problem, [0.0, 0.0], &settings)?;
    // The cost at k = 0 is the solver's first, from its first linearisation.
    let cost_before = solution.report.cost_history[0];
    if !cost_before.is_finite() {
        return Err(CalibError::Numerical {
            stage: "preliminary correction",
            reason: "non-finite cost at k = 0".into(),
        });
    }
    let termination = match solution.report.termination {
        Termination::MaxIterations => PreliminaryTermination::MaxIterations,
        Termination::DampingSaturated => PreliminaryTermination::Stalled,
        _ => PreliminaryTermination::Converged,
    };
    Ok(Minimum {
        u: solution.state,
        cost_before,
        cost_after: solution.cost,
        iterations: solution.report.accepted,
        evaluations: problem.evaluations.get(),
        termination,
    })
}

/// Largest distance of a measured point from `centre`.
pub(crate) fn data_radius(data: &CalibrationData, centre: &Vector2<f64>) -> f64 {
    data.images
        .iter()
        .flat_map(|im| im.points.iter())
        .map(|o| (o.measured - centre).norm())
        .fold(0.0, f64::max)
}

/// Template points, their normalising transform and measured points of
/// one image.
type ImagePoints = (Vec<Vector2<f64>>, Matrix3<f64>, Vec<Vector2<f64>>);

/// Homography-consistency cost (module documentation).
struct Consistency {
    /// Per usable image: template points (normalised once) and measured
    /// points.
    images: Vec<ImagePoints>,
    centre: Vector2<f64>,
    radius: f64,
}

impl TwoParameterCost for Consistency {
    fn residuals(&self, u: [f64; 2]) -> Result<DVector<f64>, CalibError> {
        let (k1, k2) = (u[0] / self.radius.powi(2), u[1] / self.radius.powi(4));
        let n: usize = self.images.iter().map(|(t, _, _)| 2 * t.len()).sum();
        let mut r = DVector::zeros(n);
        let mut row = 0;
        for (template, t_p, measured) in &self.images {
            let corrected: Vec<_> = measured
                .iter()
                .map(|m| radial_correct(m, &self.centre, k1, k2))
                .collect();
            let (homography, t_q) = fast_homography_normalised(template, t_p, &corrected)?;
            let s = t_q[(0, 0)];
            for (p, q) in template.iter().zip(&corrected) {
                let e = (homography.apply(p)? - q) * s;
                r[row] = e.x;
                r[row + 1] = e.y;
                row += 2;
            }
        }
        Ok(r)
    }
}

/// Estimates the preliminary radial correction (module documentation).
///
/// Errors: [`CalibError::Degenerate`] when the chosen method has nothing to
/// work on (straightness without lines of ≥ 3 observed LEDs, consistency
/// without an image of ≥ 5 points, or all points at the centre), data errors
/// from [`check_data`], and homography failures of the consistency cost.
pub fn estimate_preliminary(
    data: &CalibrationData,
    options: &PreliminaryOptions,
) -> Result<PreliminaryReport, CalibError> {
    check_data(data)?;
    let centre = options.centre;
    if !(centre.x.is_finite() && centre.y.is_finite()) {
        return Err(CalibError::InvalidInput {
            reason: "non-finite preliminary-correction centre".into(),
        });
    }
    let method = match options.method {
        Preliminary::Off => return Ok(PreliminaryReport::off(centre)),
        Preliminary::Auto => {
            if crate::start::straightness::usable_lines(data) > 0 {
                Preliminary::Straightness
            } else {
                Preliminary::HomographyConsistency
            }
        }
        m => m,
    };
    let radius = data_radius(data, &centre);
    if radius.is_nan() || radius <= 0.0 {
        return Err(CalibError::Degenerate {
            reason: "every measured point is at the correction centre".into(),
        });
    }
    let (minimum, terms) = match method {
        Preliminary::Straightness => {
            let cost = crate::start::straightness::StraightnessCost::new(data, centre, radius)?;
            let terms = cost.lines();
            (minimise(&cost, options.max_iterations)?, terms)
        }
        _ => {
            let images: Vec<_> = data
                .images
                .iter()
                .filter(|im| im.points.len() >= 5)
                .map(|im| {
                    let template: Vec<_> = im.points.iter().map(|o| data.template[o.led]).collect();
                    let t_p = normalizing_transform(&template)?;
                    let measured = im.points.iter().map(|o| o.measured).collect();
                    Ok((template, t_p, measured))
                })
                .collect::<Result<_, CalibError>>()?;
            if images.is_empty() {
                return Err(CalibError::Degenerate {
                    reason: "homography-consistency correction needs images of at least 5 points"
                        .into(),
                });
            }
            let terms = images.len();
            let cost = Consistency {
                images,
                centre,
                radius,
            };
            (minimise(&cost, options.max_iterations)?, terms)
        }
    };
    Ok(PreliminaryReport {
        method,
        k1: minimum.u[0] / radius.powi(2),
        k2: minimum.u[1] / radius.powi(4),
        centre,
        cost_before: minimum.cost_before,
        cost_after: minimum.cost_after,
        iterations: minimum.iterations,
        evaluations: minimum.evaluations,
        terms,
        termination: minimum.termination,
    })
}
