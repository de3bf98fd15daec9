//! The residual-structure tests of a finished fit (docs/model.md §4.7; the
//! diagnostics `model_misfit` and `gain_imbalance_suspected` of
//! [`mod@crate::diagnostics`]). The
//! image-plane residuals `r = project(θ, pose_i, X_j) − m_ij` at the solution
//! (unweighted, whatever cost was minimised) are tested for a smooth field
//! shared by all images that the model does not contain: the Gauss–Newton
//! cost decrease `Δ` of adding the field's coefficients `β` to the model
//! (`r ≈ J δ + B β`, the poses and freed parameters re-optimised with them)
//! is compared with the residual variance by an F-test. `Δ` comes from the
//! image-plane problem's arrow-shaped normal equations with the fields' columns
//! appended to the freed parameters: with `S` the Schur complement (poses
//! eliminated) and `g` the reduced gradient, `Δ = gᵀ S⁺ g`, the pseudo-inverse
//! over the eigenvalues of the unit-diagonal `S` above [`RANK_CUTOFF`] of the
//! largest (a field direction the model already has adds nothing and no
//! degree of freedom). Two fields:
//!
//! - the **cubic field**: per axis, the seven monomials `uᵃ vᵇ` of degree 2
//!   and 3, `u = 2x/Lx`, `v = 2y/Ly` (14 columns; degrees 0 and 1 are the
//!   poses' and `f, cx, cy`'s). It contains an unmodelled PSD distortion
//!   `l1 h²` about (0, 0) (the part `k1` about `(cx, cy)` cannot absorb), a
//!   missing `k3` or tangential term, and most of the effect of unequal gains;
//! - the **gain field**: the three columns `∂m/∂(g_x2, g_y1, g_y2)` of the
//!   impact-point formula (docs/model.md §1.1) at unit gains and the forward
//!   currents of the point — exactly how a small imbalance moves each point
//!   (first order: `δ(u, v) = Σ_k ε_k q_k (sx_k − u, sy_k − v)` with the
//!   bilinear shares `q_k`).
//!
//! The fields are evaluated at each point's prediction
//! `m̂ = m + r = project(θ, pose_i, X_j)`, not at the noisy measured point: a
//! column evaluated at `m` carries `∂field/∂m · noise`, correlated with the
//! residual's own noise, and a field direction nearly inside the model's
//! span (where the clean part cancels) picks that up as structure (measured:
//! F ≈ 15–20 on clean 40 dB data, F ≈ 1 at the prediction). The image plane
//! is used, not the fit's template plane, for the same reason: the
//! template-plane Jacobian itself depends on the noisy measured point. At a
//! template-plane or weighted solution the image-plane gradient over the
//! freed parameters and poses is not exactly zero; `Δ_base` (the decrease the
//! model alone would still make) is subtracted.
//!
//! With `n` coordinates, `P` parameters after adding the field and `q` its
//! effective columns, `F = (Δ_field − Δ_base)/q ÷ (SS − Δ_field)/(n − P)`.
//! The field is **significant** when both hold:
//!
//! - `F` exceeds the F(q, n − P) quantile at `p = 1e-6` ([`SIGNIFICANCE_Z`],
//!   by Paulson's normal approximation of F): about one false alarm in a
//!   million fits of a correct model under Gaussian noise, which leaves room
//!   for the approximations (heteroscedastic channel noise, unweighted
//!   residuals, a template-plane solution);
//! - the field explains at least [`MIN_EXPLAINED`] = 10 % of the residual
//!   sum of squares left by the model (`(Δ_field − Δ_base)/(SS − Δ_base)`):
//!   the systematic part is at least a third of the noise in RMS, so that a
//!   tiny but statistically certain misfit in a very large data set does not
//!   raise a warning.
//!
//! `gain_imbalance_suspected` is raised when the gains are not fitted, the
//! gain field is significant and it explains at least [`GAIN_SHARE`] (3/4)
//! of what the cubic field explains; `model_misfit` when the cubic field is
//! significant and is not explained by the gain field (the cubic field tested against
//! the gain field as base, same rules). With a known point noise σ
//! ([`DiagnosticOptions::point_sigma_mm`]), `model_misfit` is also raised
//! when the unweighted image-plane residual exceeds what σ explains: `SS/σ²`
//! above the χ²(n − P) quantile at `p = 1e-6` (Wilson–Hilferty) and the RMS
//! 25 % above σ. Nothing is tested on an exact fit (RMS below 1e-9 mm).

use nalgebra::{DMatrix, DVector, Matrix2x3, SymmetricEigen, Vector2};
use psdcal_model::psd::{electrode_currents, impact_point_gain_jacobian};
use psdcal_model::{ChannelGains, Diagnostic, DiagnosticCode, Model, PsdGeometry};
use psdcal_solver::normal_equations::{ResidualTerm, Step};
use psdcal_solver::solver::{self, Problem};
use serde::Serialize;

use super::candidate_terms::{candidate_terms, term_buffer, term_columns, CandidateTerm};
use crate::problem::calibration_problem::{CalibrationProblem, FitState};
use crate::CalibError;

/// One-sided standard-normal quantile of `p = 1e-6`: the level of every
/// statistical test here.
pub const SIGNIFICANCE_Z: f64 = 4.753_424_308_822_899;
/// Fraction of the remaining residual sum of squares a field must explain.
pub const MIN_EXPLAINED: f64 = 0.1;
/// Eigenvalues of a unit-diagonal information matrix below this fraction of
/// the largest count as zero (directions the model already has).
pub const RANK_CUTOFF: f64 = 1e-9;
/// Share of the cubic field's explained sum of squares the gain field must
/// explain for the structure to be called a gain imbalance (observed: 0.79–1
/// on imbalanced data, at most 0.6 on an unmodelled PSD distortion).
pub const GAIN_SHARE: f64 = 0.75;
/// Residual variance over the known noise variance above which the χ² test
/// may flag a misfit (RMS 25 % above σ).
pub const MISFIT_RATIO: f64 = 1.5625;

/// RMS image-plane error (mm) below which a fit is exact: nothing to test.
const EXACT_RMS_MM: f64 = 1e-9;

/// One F-test of a residual field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FieldTest {
    /// Effective columns the field adds.
    pub df1: usize,
    /// Residual degrees of freedom with the field.
    pub df2: usize,
    /// The F statistic.
    pub f: f64,
    /// Its normal equivalent (Paulson).
    pub z: f64,
    /// Fraction of the remaining residual sum of squares explained.
    pub explained: f64,
}

impl FieldTest {
    /// Significant and large enough (module documentation).
    pub fn significant(&self) -> bool {
        self.df1 > 0 && self.z > SIGNIFICANCE_Z && self.explained >= MIN_EXPLAINED
    }
}

/// What the diagnostics may use beyond the fit.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DiagnosticOptions {
    /// Known standard deviation of each coordinate of a measured point, mm
    /// (from the channels' SNR): enables the χ² test of the residual.
    pub point_sigma_mm: Option<f64>,
}

/// The diagnostics and the statistics behind them.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct DiagnosticReport {
    /// What the user should know.
    pub diagnostics: Vec<Diagnostic>,
    /// Cubic field against the model (`None`: not tested).
    pub cubic: Option<FieldTest>,
    /// Gain field against the model.
    pub gain: Option<FieldTest>,
    /// Cubic field against the model plus the gain field.
    pub beyond_gain: Option<FieldTest>,
    /// Each candidate term not fitted against the model
    /// ([`super::candidate_terms`]).
    pub terms: Vec<TermTest>,
    /// Condition number of the unit-diagonal information matrix.
    pub condition: Option<f64>,
}

impl DiagnosticReport {
    /// Whether a diagnostic with `code` was raised.
    pub fn has(&self, code: DiagnosticCode) -> bool {
        self.diagnostics.iter().any(|d| d.code == code)
    }
}

/// A fit whose residuals are image-plane errors `r = m̂ − m` (mm on the
/// sensor, unweighted), one 2-vector per observation, image after image,
/// with one pose block per image: what the residual-structure tests
/// linearise. The planar fit's image-plane [`CalibrationProblem`] and the
/// surveyed fit's problem ([`crate::surveyed::SurveyedProblem`]) are such fits.
pub trait ImagePlaneFit: Problem<State = FitState, Error = CalibError> {
    /// The PSD's active area (the fields' scale).
    fn geometry(&self) -> &PsdGeometry;
    /// Per image, its number of observations, in evaluation order.
    fn image_sizes(&self) -> Vec<usize>;
    /// The measured point `m` of observation `k` of image `i` under `model`
    /// (a gains stage may recompute it from amplitudes).
    fn measured_point(&self, model: &Model, i: usize, k: usize)
        -> Result<Vector2<f64>, CalibError>;
    /// The flat model columns of the freed parameters.
    fn freed_columns(&self) -> Vec<usize>;
}

impl ImagePlaneFit for CalibrationProblem<'_> {
    fn geometry(&self) -> &PsdGeometry {
        &self.data().geometry
    }

    fn freed_columns(&self) -> Vec<usize> {
        self.columns().to_vec()
    }

    fn image_sizes(&self) -> Vec<usize> {
        self.data().images.iter().map(|i| i.points.len()).collect()
    }

    fn measured_point(
        &self,
        model: &Model,
        i: usize,
        k: usize,
    ) -> Result<Vector2<f64>, CalibError> {
        self.measured(model, i, k).map(|(m, _)| m).map_err(|e| {
            crate::problem::calibration_problem::point_error(
                self.data(),
                i,
                self.data().images[i].points[k].led,
                e,
            )
        })
    }
}

/// The residual-structure tests (module documentation) of any
/// image-plane fit at its solution `state`: `test_gains` when the fit has
/// no gains of its own (the gain field is then tested), `gain_advice` what
/// `gain_imbalance_suspected` tells the user to do.
pub fn diagnose_residuals<P: ImagePlaneFit>(
    problem: &P,
    state: &FitState,
    test_gains: bool,
    extra: &DiagnosticOptions,
    gain_advice: &str,
) -> DiagnosticReport {
    let mut report = DiagnosticReport::default();
    // One linearisation of the fit's own problem with both fields appended
    // serves the structure tests.
    if let Some(lin) = Linearised::new(problem, state, test_gains) {
        structure(
            &problem.image_sizes(),
            extra,
            &lin,
            gain_advice,
            &mut report,
        );
    }
    report
}

/// The fit's problem linearised at the solution with the fields appended.
struct Linearised {
    /// Freed parameters.
    p: usize,
    /// Whether the gain field's columns follow the cubic field's.
    gain: bool,
    /// The candidate terms, whose columns follow the fields'.
    terms: Vec<CandidateTerm>,
    /// Schur complement over `[freed | cubic | gain | terms]`, poses
    /// eliminated.
    s: DMatrix<f64>,
    /// The reduced gradient.
    g: DVector<f64>,
    /// `Σ ‖m̂ − m‖²`: the image-plane residual (unweighted).
    image_ss: f64,
}

impl Linearised {
    fn new<P: ImagePlaneFit>(problem: &P, state: &FitState, gain: bool) -> Option<Self> {
        let terms = candidate_terms(&state.model, &problem.freed_columns());
        let term_len: usize = terms.iter().map(|t| t.columns.len()).sum();
        let augmented = Augmented {
            inner: problem,
            sizes: problem.image_sizes(),
            q: field_columns(gain) + term_len,
            gain,
            terms: &terms,
            image_ss: std::cell::Cell::new(0.0),
        };
        let ne = solver::normal_equations(&augmented, state, None).ok()?;
        let s = ne.schur_complement()?;
        let p = problem.global_len();
        let mut g = ne.g_a.clone();
        for i in 0..ne.v.len() {
            let v_inv = ne.v[i].cholesky()?.inverse();
            let gb = DVector::from_iterator(6, (v_inv * ne.g_b[i]).iter().copied());
            g -= &ne.w[i] * gb;
        }
        let image_ss = augmented.image_ss.get();
        Some(Self {
            p,
            gain,
            terms,
            s,
            g,
            image_ss,
        })
    }

    /// `(Δ, rank)` over the freed parameters and candidate term `t`.
    fn explained_by_term(&self, t: usize) -> (f64, usize) {
        let start = self.p
            + field_columns(self.gain)
            + self.terms[..t]
                .iter()
                .map(|t| t.columns.len())
                .sum::<usize>();
        let mut cols: Vec<usize> = (0..self.p).collect();
        cols.extend(start..start + self.terms[t].columns.len());
        explained(&self.s, &self.g, &cols)
    }

    /// `(Δ, rank)` over the freed parameters and the chosen fields.
    fn explained(&self, cubic: bool, gain: bool) -> (f64, usize) {
        let mut cols: Vec<usize> = (0..self.p).collect();
        if cubic {
            cols.extend(self.p..self.p + CUBIC_COLUMNS);
        }
        if gain && self.gain {
            cols.extend(self.p + CUBIC_COLUMNS..self.p + CUBIC_COLUMNS + GAIN_COLUMNS);
        }
        explained(&self.s, &self.g, &cols)
    }
}

/// The residual-structure tests.
fn structure(
    sizes: &[usize],
    extra: &DiagnosticOptions,
    lin: &Linearised,
    advice: &str,
    report: &mut DiagnosticReport,
) {
    let points: usize = sizes.iter().sum();
    if lin.image_ss <= EXACT_RMS_MM * EXACT_RMS_MM * points as f64 {
        return;
    }
    let (n, poses, p) = (2 * points, 6 * sizes.len(), lin.p);
    let ss = lin.image_ss;
    let base = lin.explained(false, false);
    let cubic = lin.explained(true, false);
    let t = field_test(ss, n, poses, base, cubic);
    report.cubic = Some(t);
    let mut gain_explains = false;
    if lin.gain {
        let gain = lin.explained(false, true);
        let both = lin.explained(true, true);
        let g = field_test(ss, n, poses, base, gain);
        report.gain = Some(g);
        report.beyond_gain = Some(field_test(ss, n, poses, gain, both));
        gain_explains = g.significant() && (gain.0 - base.0) >= GAIN_SHARE * (cubic.0 - base.0);
    }
    if gain_explains {
        let t = report.gain.unwrap_or(FIELD_NONE);
        report.diagnostics.push(Diagnostic::warning(
            DiagnosticCode::GainImbalanceSuspected,
            format!(
                "the residuals follow the pattern of unequal channel gains ({:.0} % of the residual, \
                 F = {:.1} on {} and {} degrees of freedom); {advice}",
                100.0 * t.explained,
                t.f,
                t.df1,
                t.df2
            ),
        ));
    }
    let term_gains: Vec<f64> = (0..lin.terms.len())
        .map(|t| lin.explained_by_term(t))
        .map(|full| {
            report.terms.push(TermTest {
                term: String::new(),
                test: field_test(ss, n, poses, base, full),
            });
            (full.0 - base.0).max(0.0)
        })
        .collect();
    for (t, term) in report.terms.iter_mut().zip(&lin.terms) {
        t.term = term.names.join(",");
    }
    let misfit = if gain_explains {
        report.beyond_gain
    } else {
        report.cubic
    };
    let cubic_gain = (cubic.0 - base.0).max(0.0);
    let cause = named_cause(&report.terms, cubic_gain, &term_gains);
    if let Some(t) = cause {
        let term = &report.terms[t];
        report.diagnostics.push(Diagnostic::warning(
            DiagnosticCode::ModelMisfit,
            format!(
                "the residuals have a structure across the sensor shared by the images that \
                 the term {} explains ({:.0} % of the residual, F = {:.1} on {} and {} degrees \
                 of freedom): add {} to --fit",
                term.term,
                100.0 * term.test.explained,
                term.test.f,
                term.test.df1,
                term.test.df2,
                term.term
            ),
        ));
    } else if let Some(t) = misfit.filter(FieldTest::significant) {
        let tried = if report.terms.is_empty() {
            "every term of the model is fitted".to_string()
        } else {
            format!(
                "its terms not fitted explain little of it: {}",
                shares(&report.terms)
            )
        };
        report.diagnostics.push(Diagnostic::warning(
            DiagnosticCode::ModelMisfit,
            format!(
                "the residuals have a smooth structure across the sensor shared by the images \
                 ({:.0} % of the residual, F = {:.1} on {} and {} degrees of freedom) that the \
                 model cannot follow ({tried}): distortion beyond the model's stages (a \
                 wide-angle lens, a non-radial PSD non-linearity: measure a PSD map with \
                 psdcal psd-map) or errors in the template's coordinates; σ covers the \
                 noise, not this structure: f and the centre may differ from another \
                 model's by more than 3σ",
                100.0 * t.explained,
                t.f,
                t.df1,
                t.df2
            ),
        ));
    } else if let Some(sigma) = extra.point_sigma_mm.filter(|s| *s > 0.0) {
        let dof = n.saturating_sub(poses + p);
        if dof > 0 {
            let ratio = lin.image_ss / dof as f64 / (sigma * sigma);
            let z = wilson_hilferty(lin.image_ss / (sigma * sigma), dof as f64);
            if z > SIGNIFICANCE_Z && ratio >= MISFIT_RATIO {
                report.diagnostics.push(Diagnostic::warning(
                    DiagnosticCode::ModelMisfit,
                    format!(
                        "the image-plane RMS per coordinate ({:.3e} mm) is {:.2}× the known noise \
                         ({sigma:.3e} mm): the model does not explain the data to the noise level",
                        (lin.image_ss / dof as f64).sqrt(),
                        ratio.sqrt()
                    ),
                ));
            }
        }
    }
}

const FIELD_NONE: FieldTest = FieldTest {
    df1: 0,
    df2: 0,
    f: 0.0,
    z: 0.0,
    explained: 0.0,
};

/// `(Δ, rank)` of each model as returned by [`explained`]; `ss` the residual
/// sum of squares, `n` coordinates, `poses` parameters.
fn field_test(
    ss: f64,
    n: usize,
    poses: usize,
    base: (f64, usize),
    full: (f64, usize),
) -> FieldTest {
    let df1 = full.1.saturating_sub(base.1);
    let df2 = n.saturating_sub(poses + full.1);
    let remaining = (ss - full.0).max(0.0);
    if df1 == 0 || df2 == 0 || remaining <= 0.0 {
        return FieldTest {
            df1,
            df2,
            ..FIELD_NONE
        };
    }
    let gain = (full.0 - base.0).max(0.0);
    let f = (gain / df1 as f64) / (remaining / df2 as f64);
    FieldTest {
        df1,
        df2,
        f,
        z: paulson(f, df1 as f64, df2 as f64),
        explained: gain / (ss - base.0).max(f64::MIN_POSITIVE),
    }
}

/// Paulson's normal approximation of an F(d1, d2) statistic.
fn paulson(f: f64, d1: f64, d2: f64) -> f64 {
    let (a, b) = (2.0 / (9.0 * d1), 2.0 / (9.0 * d2));
    let c = cube_root(f);
    ((1.0 - b) * c - (1.0 - a)) / (a + c * c * b).sqrt()
}

/// Wilson–Hilferty normal approximation of a χ²(k) statistic `x`.
fn wilson_hilferty(x: f64, k: f64) -> f64 {
    let a = 2.0 / (9.0 * k);
    (cube_root(x / k) - (1.0 - a)) / a.sqrt()
}

/// The real cube root through the system's `pow`: `f64::cbrt` binds to
/// compiler_builtins' `cbrt`, whose first call detects the CPU's features
/// (`cpuid`, 13 µs an instruction under a hypervisor, measured here), which
/// costs more than these statistics.
fn cube_root(x: f64) -> f64 {
    if x < 0.0 {
        -(-x).powf(1.0 / 3.0)
    } else {
        x.powf(1.0 / 3.0)
    }
}

/// The Gauss–Newton decrease `gᵀ S⁺ g` over the columns `cols` and the rank
/// of `S` there (unit-diagonal eigenvalues above [`RANK_CUTOFF`]).
fn explained(s: &DMatrix<f64>, g: &DVector<f64>, cols: &[usize]) -> (f64, usize) {
    let m = cols.len();
    if m == 0 {
        return (0.0, 0);
    }
    let d: Vec<f64> = cols
        .iter()
        .map(|&c| {
            let v = s[(c, c)];
            if v > 0.0 {
                1.0 / v.sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let scaled = DMatrix::from_fn(m, m, |i, j| s[(cols[i], cols[j])] * d[i] * d[j]);
    let gs = DVector::from_fn(m, |i, _| g[cols[i]] * d[i]);
    let eig = SymmetricEigen::new(scaled);
    let top = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
    let mut delta = 0.0;
    let mut rank = 0;
    for (k, &l) in eig.eigenvalues.iter().enumerate() {
        if l > RANK_CUTOFF * top {
            let proj = eig.eigenvectors.column(k).dot(&gs);
            delta += proj * proj / l;

            rank += 1;
        }
    }
    (delta, rank)
}

/// Columns of the cubic field (per axis, the seven monomials of degree 2
/// and 3; degrees 0 and 1 are the poses' and `f, cx, cy`'s).
const CUBIC_COLUMNS: usize = 14;
/// Columns of the gain field.
const GAIN_COLUMNS: usize = 3;

/// Columns of the fields: the cubic field's, and the gain field's when
/// tested.
fn field_columns(gain: bool) -> usize {
    CUBIC_COLUMNS + if gain { GAIN_COLUMNS } else { 0 }
}

/// The fields' columns at predicted point `m`, column-major (2 × q): the
/// cubic field, then (when `gain`) the gain field.
fn field_values(geometry: &PsdGeometry, m: &Vector2<f64>, gain: bool, out: &mut [f64]) {
    let (hx, hy) = (0.5 * geometry.lx, 0.5 * geometry.ly);
    let (u, v) = (m.x / hx, m.y / hy);
    let mut k = 0;
    for degree in 2..=3 {
        for a in 0..=degree {
            let phi = u.powi(a) * v.powi(degree - a);
            out[2 * k] = hx * phi;
            out[2 * k + 1] = 0.0;
            out[2 * (k + 7)] = 0.0;
            out[2 * (k + 7) + 1] = hy * phi;
            k += 1;
        }
    }
    if gain {
        let currents = electrode_currents(geometry, m, 1.0);
        let j: Matrix2x3<f64> =
            impact_point_gain_jacobian(geometry, &currents, &ChannelGains::default())
                .map(|(_, j)| j)
                .unwrap_or_else(|_| Matrix2x3::zeros());
        out[2 * CUBIC_COLUMNS..2 * (CUBIC_COLUMNS + GAIN_COLUMNS)].copy_from_slice(j.as_slice());
    }
}

/// The image-plane problem with the fields' columns appended to the freed
/// parameters (only linearised, never solved). A field is a displacement
/// `δm = B β` of every measured point; the image-plane residual
/// `project(θ, pose_i, X_j) − m` moves by `−B β` (the sign is immaterial).
/// The columns are evaluated at each point's prediction `m̂ = m + r`.
struct Augmented<'p, P> {
    inner: &'p P,
    /// Per image, its number of observations.
    sizes: Vec<usize>,
    /// Columns appended.
    q: usize,
    /// Whether the gain field's columns follow the cubic field's.
    gain: bool,
    /// The candidate terms, whose columns follow the fields'.
    terms: &'p [CandidateTerm],
    /// `Σ ‖r‖²` of the last evaluation.
    image_ss: std::cell::Cell<f64>,
}

impl<P: ImagePlaneFit> Problem for Augmented<'_, P> {
    type State = FitState;
    type Error = CalibError;

    fn global_len(&self) -> usize {
        self.inner.global_len() + self.q
    }

    fn block_count(&self) -> usize {
        self.inner.block_count()
    }

    fn evaluate(
        &self,
        state: &FitState,
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>),
    ) -> Result<(), CalibError> {
        let p = self.inner.global_len();
        let mut a = vec![0.0; 2 * (p + CUBIC_COLUMNS + GAIN_COLUMNS) + 2 * self.q];
        let term_start = 2 * (p + field_columns(self.gain));
        let mut term_jacobian = term_buffer(&state.model, self.terms);
        let (mut i, mut k) = (0, 0);
        let mut ss = 0.0;
        let mut failed = None;
        self.inner.evaluate(state, jacobians, &mut |t| {
            while k >= self.sizes[i] {
                i += 1;
                k = 0;
            }
            let r = Vector2::new(t.r[0], t.r[1]);
            ss += r.norm_squared();
            if jacobians {
                match self.inner.measured_point(&state.model, i, k) {
                    Ok(m) => {
                        field_values(self.inner.geometry(), &(m + r), self.gain, &mut a[2 * p..]);
                        term_columns(
                            &state.model,
                            &(m + r),
                            self.terms,
                            &mut term_jacobian,
                            &mut a[term_start..],
                        );
                    }
                    Err(e) => failed = Some(e),
                }
                a[..2 * p].copy_from_slice(t.a);
                visit(&ResidualTerm {
                    r: t.r,
                    a: &a[..2 * (p + self.q)],
                    block: t.block,
                });
            } else {
                visit(t);
            }
            k += 1;
        })?;
        if let Some(e) = failed {
            return Err(e);
        }
        self.image_ss.set(ss);
        Ok(())
    }

    /// Never stepped: the augmented problem is only linearised.
    fn apply_step(&self, _: &FitState, _: &Step) -> Option<FitState> {
        None
    }
}

/// How much one candidate term would explain.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TermTest {
    /// The term's parameters, comma-separated (as `--fit` names them).
    pub term: String,
    /// Its F-test against the model as fitted.
    pub test: FieldTest,
}

/// The candidate explaining most of the residual, when one is significant
/// and explains at least half of what the cubic field does (`cubic_gain`,
/// its decrease over the model): the cause to name.
pub(crate) fn named_cause(terms: &[TermTest], cubic_gain: f64, gains: &[f64]) -> Option<usize> {
    let best = (0..terms.len()).max_by(|&a, &b| gains[a].total_cmp(&gains[b]))?;
    (terms[best].test.significant() && gains[best] >= 0.5 * cubic_gain).then_some(best)
}

/// "k3 12 %, p1,p2 3 %": each candidate's share of the residual.
pub(crate) fn shares(terms: &[TermTest]) -> String {
    terms
        .iter()
        .map(|t| format!("{} {:.0} %", t.term, 100.0 * t.test.explained))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::cube_root;

    #[test]
    fn cube_root_agrees_with_cbrt() {
        for k in -40..=40 {
            let x = 1.7f64.powi(k) * if k % 3 == 0 { -1.0 } else { 1.0 };
            let (got, exact) = (cube_root(x), x.cbrt());
            assert!(
                (got - exact).abs() <= 4.0 * f64::EPSILON * exact.abs(),
                "{x}: {got} vs {exact}"
            );
        }
        assert_eq!(cube_root(0.0), 0.0);
        assert_eq!(cube_root(8.0).round(), 2.0);
    }
}
