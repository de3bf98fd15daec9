//! The robust start of the refinement: preliminary correction, homographies,
//! the closed form, and a focal-length search as its fallback (docs/model.md
//! §4.1–4.5; the paper's (P17)–(P28), (P30), (P36)–(P38)).
//!
//! 1. Checks: at least 3 images with ≥ 4 points ([`CalibError::TooFewImages`]),
//!    every image with ≥ 4 points ([`CalibError::TooFewPoints`]), valid LED
//!    indices, finite numbers.
//! 2. Preliminary radial correction `p = c0 + (m − c0)(1 + k1 r² + k2 r⁴)`
//!    ([`crate::preliminary`]; `Auto` that cannot run falls back to no
//!    correction, with a note).
//! 3. One homography per image from the corrected points (DLT (P17)–(P18),
//!    Hartley normalisation (P36)–(P38) unless switched off). Collinear LEDs
//!    are refused here.
//! 4. The closed form ([`crate::zhang`], (P19)–(P25) corrected). It is a
//!    *candidate* when `f² > 0`, `f` lies in `[0.2, 50] ×` the sensor diagonal
//!    (or in `[g/2, 2g]` for a focal guess `g`) and the centre lies on the
//!    active area.
//! 5. The objective, for intrinsics `(f, cx, cy)` held fixed:
//!
//!    ```text
//!    J(f, cx, cy) = min over k1 and the poses of
//!                   Σ_images Σ_points ‖back_project(model, pose_i, m_ij) − P_j‖²   (mm²)
//!    ```
//!
//!    the template-plane error of (P29) on the *measured* points `m_ij`,
//!    with `model = (f, cx, cy, k1, k2 = preliminary k2)`. The poses start from
//!    the homographies ((P26)–(P28), nearest rotation) and `k1` from the
//!    preliminary estimate; the minimisation is a Levenberg–Marquardt with the
//!    poses eliminated by the Schur complement (one shared parameter, so the
//!    reduced system is a scalar). Freeing `k1` is what makes the start
//!    survive uncorrected distortion. Measured on the paper's lenses, raw
//!    noise-free points, centre `(0, 0)`, four image sets each: with the poses
//!    taken straight from the homographies and `k1 = 0`, the minimum of this
//!    error over `f` lies at 12.6–15.8 mm for lens 1 (truth 25) and 3.2–5.1 mm
//!    for lens 2 (truth 8); with the poses refined but `k1 = 0`, at
//!    17.1–21.5 mm and 5.5–6.4 mm; with `k1` free as here, within 6 % and
//!    12 % of the truth.
//! 6. The closed form refined over `f, cx, cy, k1, k2` and the poses. On a
//!    set of more than six images the long descent from the closed form runs
//!    on [`REFINE_SUBSET_IMAGES`] images spread over the set; the whole set
//!    then starts from that minimum, each other image's pose from the
//!    homography of its points corrected by the subset's model, with little
//!    damping (`focal_profile::NEAR_LAMBDA`): on 12 images of lens 2 at
//!    40 dB, 11–23 subset iterations (measured when the subset started at
//!    damping 1e-3) and 3 on the whole set, against 10–17 on the whole set
//!    from the closed form (the damping of the strongly correlated
//!    directions decays by a factor 3 an iteration, which near the minimum
//!    cost 5–6 of them). The subset's descent itself starts with little
//!    damping (`focal_profile::REFINED_LAMBDA`): the closed form is near
//!    enough for Gauss–Newton steps, and a step that overshoots is rejected
//!    and damped as usual.
//!    The closed-form candidate, when there is one and `J` at 0.5, 0.7, 1.4
//!    and 2 × its `f` (with its centre and with the centre at (0, 0)) is not
//!    below half its own (it sits in the right basin),
//!    is the start: the refinement that follows corrects its error (the
//!    robustness experiment of `tests/robustness.rs` judges this against a
//!    multi-start search).
//!    Without a candidate (or with `use_closed_form = false`), the focal
//!    search: `J` on a log-spaced grid (41 points over 1–1000 mm, or 13 over
//!    `[g/2, 2g]` with a focal guess), refined by golden-section search in
//!    `ln f` around the best grid point, once with the centre at `(0, 0)` and
//!    once at the closed-form centre when that is on the active area; the
//!    lower `J` wins (route `FocalSearch`, or `FocalGuess` with a guess). On
//!    large sets the search uses at most [`SEARCH_IMAGES`] images spread over
//!    the set, so its cost does not grow with the number of images.
//! 7. Identifiability: after a search, if `J` at half and at double the
//!    chosen `f` exceeds `J(f)` by no more than [`FLAT_PROFILE`]` · J(f)`
//!    (plus a rounding floor), the profile is flat in `f`: the template poses
//!    are all parallel to the sensor and [`CalibError::Degenerate`] says so.
//!    With noise a nearly parallel set gives a poorly determined `f`, which
//!    the covariance of the refined fit reports ([`mod@crate::calibrate`]).
//!    `focal_sensitivity` reports the Δχ² of that test with
//!    `σ² = J(f)/(2·points − 6·images − 4)`.
//!
//! *Starting model.* `f, cx, cy` of the route; `k1` from the minimisation of
//! step 5 at those intrinsics (a lens radial coefficient centred on
//! `(cx, cy)`, consistent with the returned poses and the measured points);
//! `k2` the preliminary estimate (0 when off); `k3, p1, p2, l1, l2, skew` zero.

use nalgebra::Vector2;
use psdcal_model::{Model, Pose, PsdGeometry, MIN_POINTS_PER_IMAGE};

use crate::start::focal_profile::{subset_images, Precision, Problem, Profile};
pub use crate::start::focal_profile::{FocalSearchReport, REFINE_SUBSET_IMAGES};
use crate::start::homography::{fit_homography, HomographyOptions};
use crate::start::preliminary::{
    check_data, estimate_preliminary, Preliminary, PreliminaryOptions, PreliminaryReport,
};
use crate::start::zhang::{closed_form, ClosedFormSolution};
use crate::warning::FitWarning;
use crate::{CalibError, CalibrationData, ImageObservations};
use psdcal_model::CostKind;

/// Minimum number of images for a calibration (one definition, in psdcal-model).
pub use psdcal_model::MIN_IMAGES;

/// Relative change of `J` under halving or doubling `f` below which the
/// profile counts as flat (`f` undetermined).
pub const FLAT_PROFILE: f64 = 1e-6;

/// Multiples of the closed-form `f` at which the profile is compared with
/// the closed form's own value.
const NEIGHBOUR_FACTORS: [f64; 4] = [0.5, 0.7, 1.4, 2.0];

/// Most images the focal search evaluates.
pub const SEARCH_IMAGES: usize = 24;

/// Most images the preliminary correction is estimated from.
pub const PRELIMINARY_IMAGES: usize = 8;

/// Most images the basin check of the refined closed form evaluates: it
/// compares values a factor two apart, which a few images decide.
pub const CHECK_IMAGES: usize = 6;

/// Options of [`initialize`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitOptions {
    /// Preliminary distortion correction (default `Auto`).
    pub preliminary: Preliminary,
    /// Fixed centre of the preliminary correction, mm (default `(0, 0)`).
    pub preliminary_centre: Vector2<f64>,
    /// Hartley normalisation of the homographies (default `true`).
    pub normalize: bool,
    /// A focal-length guess, mm: narrows the plausible range and the search
    /// to `[g/2, 2g]`.
    pub focal_guess: Option<f64>,
    /// Try the closed form (default `true`); `false` uses the search only.
    pub use_closed_form: bool,
    /// Refine the closed-form start over `k1` and the poses before handing
    /// it on, and check it against its neighbours (default `true`). `false`
    /// reproduces the paper's start — the closed-form intrinsics whenever
    /// they are plausible, the preliminary `k1, k2` and the poses of the
    /// homographies — for studies that compare iteration counts with it.
    pub refine_start: bool,
    /// Fall back to the focal search when the closed form gives no plausible
    /// start (default `true`); `false` makes that case an error instead (the
    /// global search's cold starts, which have other starts to compare with).
    pub search_fallback: bool,
}

impl Default for InitOptions {
    fn default() -> Self {
        Self {
            preliminary: Preliminary::Auto,
            preliminary_centre: Vector2::zeros(),
            normalize: true,
            focal_guess: None,
            use_closed_form: true,
            refine_start: true,
            search_fallback: true,
        }
    }
}

/// How the starting intrinsics were obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InitRoute {
    /// The closed form was accepted.
    ClosedForm,
    /// The wide focal search (1–1000 mm).
    FocalSearch,
    /// The narrow search around the focal guess.
    FocalGuess,
}

/// What [`initialize`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct InitReport {
    /// The route taken.
    pub route: InitRoute,
    /// The closed-form solution, also when rejected (`None` if it could not
    /// be computed or was not tried).
    pub closed_form: Option<ClosedFormSolution>,
    /// `J` at the closed-form intrinsics, mm², when it is a candidate.
    pub closed_form_cost: Option<f64>,
    /// Why the closed form was rejected (`None` when accepted).
    pub closed_form_rejection: Option<String>,
    /// The focal search.
    pub search: Option<FocalSearchReport>,
    /// The preliminary correction.
    pub preliminary: PreliminaryReport,
    /// Why an `Auto` preliminary correction was skipped, if it was.
    pub preliminary_note: Option<FitWarning>,
    /// Per image: RMS transfer error of its homography (corrected points), mm.
    pub homography_rms: Vec<f64>,
    /// `J` at the start, mm² (template-plane sum of squares).
    pub cost: f64,
    /// RMS template-plane error at the start, mm per point.
    pub rms_template_mm: f64,
    /// After a focal search: `(min(J(f/2), J(2f)) − J(f)) / σ²` with
    /// `σ² = J(f)/(2·points − 6·images − 4)`, how strongly the data fix `f`
    /// (a Δχ²; `+∞` for an exact fit); NaN when the closed form was used.
    pub focal_sensitivity: f64,
}

/// The starting point of the refinement.
#[derive(Debug, Clone, PartialEq)]
pub struct Initialization {
    /// `f, cx, cy, k1, k2` (module documentation), the standard chain.
    pub model: Model,
    /// One `sensor_from_template` per image, in `data.images` order.
    pub poses: Vec<Pose>,
    /// What was done.
    pub report: InitReport,
}

/// Names the image in a homography error.
fn name_image(e: CalibError, id: &str) -> CalibError {
    match e {
        CalibError::TooFewPoints { points, .. } => CalibError::TooFewPoints {
            image: id.to_string(),
            points,
        },
        CalibError::Degenerate { reason } => CalibError::Degenerate {
            reason: format!("image '{id}': {reason}"),
        },
        other => other,
    }
}

/// Computes the starting model and poses (module documentation).
pub fn initialize(
    data: &CalibrationData,
    options: &InitOptions,
) -> Result<Initialization, CalibError> {
    check_input(data, options)?;
    let (preliminary, preliminary_note) = preliminary_correction(data, options)?;
    let (problem, homography_rms) = homography_problem(data, options, &preliminary)?;
    let mut closed = closed_form_start(&problem, options, &data.geometry);
    check_basin(data, &problem, options, &homography_rms, &mut closed);
    let search = focal_search(&problem, options, &data.geometry, &closed)?;
    let (route, f, cx, cy) = choose_route(options, &closed, search)?;
    if route == InitRoute::ClosedForm {
        closed.rejection = None;
    }
    let start = starting_profile(&problem, options, route, &mut closed, (f, cx, cy))?;
    let focal_sensitivity = if route != InitRoute::ClosedForm {
        focal_sensitivity(data, &problem, options, &start, (f, cx, cy))?
    } else {
        f64::NAN
    };
    start.model.validate()?;
    let n_points = data.point_count() as f64;
    Ok(Initialization {
        model: Model::standard(&start.model),
        poses: start.poses,
        report: InitReport {
            route,
            closed_form: closed.solution,
            closed_form_cost: closed.cost,
            closed_form_rejection: closed.rejection,
            search,
            preliminary,
            preliminary_note,
            homography_rms,
            cost: start.cost,
            rms_template_mm: (start.cost / n_points).sqrt(),
            focal_sensitivity,
        },
    })
}

/// Step 1, the checks of the module documentation: enough images of enough
/// points, a valid focal guess and active area.
fn check_input(data: &CalibrationData, options: &InitOptions) -> Result<(), CalibError> {
    check_data(data)?;
    let usable = data
        .images
        .iter()
        .filter(|im| im.points.len() >= MIN_POINTS_PER_IMAGE)
        .count();
    if usable < MIN_IMAGES {
        return Err(CalibError::TooFewImages {
            usable,
            needed: MIN_IMAGES,
        });
    }
    if let Some(im) = data
        .images
        .iter()
        .find(|im| im.points.len() < MIN_POINTS_PER_IMAGE)
    {
        return Err(CalibError::TooFewPoints {
            image: im.id.clone(),
            points: im.points.len(),
        });
    }
    if let Some(g) = options.focal_guess {
        if !(g > 0.0 && g.is_finite()) {
            return Err(CalibError::InvalidInput {
                reason: format!("focal guess must be finite and positive, got {g}"),
            });
        }
    }
    let geometry = data.geometry;
    if !(geometry.lx > 0.0
        && geometry.ly > 0.0
        && geometry.lx.is_finite()
        && geometry.ly.is_finite())
    {
        return Err(CalibError::InvalidInput {
            reason: "the PSD's active area must be finite and positive".into(),
        });
    }
    Ok(())
}

/// Step 2, the preliminary correction, with the note of an `Auto` correction
/// that could not run (then none).
fn preliminary_correction(
    data: &CalibrationData,
    options: &InitOptions,
) -> Result<(PreliminaryReport, Option<FitWarning>), CalibError> {
    let prelim_options = PreliminaryOptions {
        method: options.preliminary,
        centre: options.preliminary_centre,
        ..PreliminaryOptions::default()
    };
    // The rough correction is estimated on at most PRELIMINARY_IMAGES images
    // spread over the set: two coefficients need few images, and its cost
    // then does not grow with the set.
    // Images of ≥ 5 points (what the consistency cost uses) when there are any.
    let rich = |im: &ImageObservations| im.points.len() >= 5;
    let preliminary_data = if data.images.iter().any(rich) {
        subset_images(data, PRELIMINARY_IMAGES, &rich)
    } else {
        subset_images(data, PRELIMINARY_IMAGES, &|_| true)
    };
    match estimate_preliminary(&preliminary_data, &prelim_options) {
        Ok(r) => Ok((r, None)),
        Err(e) if options.preliminary == Preliminary::Auto => Ok((
            PreliminaryReport::off(options.preliminary_centre),
            Some(FitWarning::PreliminarySkipped {
                reason: e.to_string(),
            }),
        )),
        Err(e) => Err(e),
    }
}

/// Step 3, the homographies of the corrected points, and the start's objective
/// `J` on them (with each image's RMS transfer error).
fn homography_problem(
    data: &CalibrationData,
    options: &InitOptions,
    preliminary: &PreliminaryReport,
) -> Result<(Problem, Vec<f64>), CalibError> {
    let corrected = preliminary.correct_data(data);
    let template: Vec<Vec<_>> = data
        .images
        .iter()
        .map(|im| im.points.iter().map(|o| data.template[o.led]).collect())
        .collect();
    let hopt = HomographyOptions {
        normalize: options.normalize,
    };
    let mut homographies = Vec::with_capacity(data.images.len());
    let mut homography_rms = Vec::with_capacity(data.images.len());
    for ((im, tpl), img) in data.images.iter().zip(&template).zip(&corrected) {
        let fit = fit_homography(tpl, img, &hopt).map_err(|e| name_image(e, &im.id))?;
        homographies.push(fit.homography);
        homography_rms.push(fit.rms);
    }
    let n_points = data.point_count() as f64;
    let tpl_scale = data.template.iter().map(|p| p.norm()).fold(1.0, f64::max);
    let problem = Problem {
        data: subset_images(data, usize::MAX, &|_| true),
        homographies,
        k1_start: preliminary.k1,
        k2: preliminary.k2,
        floor: n_points * (1e-9 * tpl_scale).powi(2),
    };
    Ok((problem, homography_rms))
}

/// The closed form as a start (steps 4 and 6): the solution, and its cost
/// and refined profile when it is a candidate, or why it is not.
struct ClosedFormStart {
    /// The closed-form solution, also when rejected.
    solution: Option<ClosedFormSolution>,
    /// `J` at the refined closed form, when it is a candidate.
    cost: Option<f64>,
    /// Why it was rejected.
    rejection: Option<String>,
    /// `(f, cx, cy, J)` of the candidate (`J` NaN when not refined).
    candidate: Option<(f64, f64, f64, f64)>,
    /// The refined closed form, while it is the candidate.
    profile: Option<Profile>,
}

/// Whether the centre `(cx, cy)` lies on the active area.
fn on_area(geometry: &PsdGeometry, cx: f64, cy: f64) -> bool {
    cx.abs() <= 0.5 * geometry.lx && cy.abs() <= 0.5 * geometry.ly
}

/// Step 4, the closed-form candidate: plausible `f` and centre, refined over
/// `f, cx, cy, k1` and the poses (unless `refine_start` is off).
fn closed_form_start(
    problem: &Problem,
    options: &InitOptions,
    geometry: &PsdGeometry,
) -> ClosedFormStart {
    let diagonal = geometry.lx.hypot(geometry.ly);
    let (f_lo, f_hi) = match options.focal_guess {
        Some(g) => (0.5 * g, 2.0 * g),
        None => (0.2 * diagonal, 50.0 * diagonal),
    };
    let on_area = |cx: f64, cy: f64| on_area(geometry, cx, cy);
    let mut closed: Option<ClosedFormSolution> = None;
    let mut closed_cost = None;
    let mut rejection: Option<String> = None;
    let mut candidate = None;
    let mut closed_profile: Option<Profile> = None;
    if options.use_closed_form {
        match closed_form(&problem.homographies) {
            Err(e) => rejection = Some(e.to_string()),
            Ok(sol) => {
                closed = Some(sol);
                match sol.focal_length() {
                    Err(e) => rejection = Some(e.to_string()),
                    Ok(f) if !(f >= f_lo && f <= f_hi) => {
                        rejection = Some(format!(
                            "closed-form f = {f:.4} mm is outside the plausible range [{f_lo:.3}, {f_hi:.3}] mm"
                        ))
                    }
                    Ok(_) if !on_area(sol.cx, sol.cy) => {
                        rejection = Some(format!(
                            "closed-form centre ({:.4}, {:.4}) mm is off the active area",
                            sol.cx, sol.cy
                        ))
                    }
                    Ok(f) if !options.refine_start => {
                        candidate = Some((f, sol.cx, sol.cy, f64::NAN));
                    }
                    // The closed form refined over f, cx, cy, k1 and the poses.
                    Ok(f) => match problem.refined(f, sol.cx, sol.cy) {
                        Err(e) => rejection = Some(format!("closed-form poses fail: {e}")),
                        Ok(p) => {
                            let k = &p.model.intrinsics;
                            if !(p.converged && k.f >= f_lo && k.f <= f_hi && on_area(k.cx, k.cy)) {
                                rejection = Some(format!(
                                    "the closed form (f = {f:.4} mm) refines to f = {:.4} mm, centre \
                                     ({:.3}, {:.3}) mm{}",
                                    k.f,
                                    k.cx,
                                    k.cy,
                                    if p.converged { "" } else { " without converging" }
                                ));
                            } else {
                                closed_cost = Some(p.cost);
                                candidate = Some((k.f, k.cx, k.cy, p.cost));
                                closed_profile = Some(p);
                            }
                        }
                    },
                }
            }
        }
    } else {
        rejection = Some("closed form not tried (use_closed_form = false)".into());
    }
    ClosedFormStart {
        solution: closed,
        cost: closed_cost,
        rejection,
        candidate,
        profile: closed_profile,
    }
}

/// Step 6, the basin check: the refined closed form must also be the lowest
/// basin at the scale of its own error, else it is no candidate.
fn check_basin(
    data: &CalibrationData,
    problem: &Problem,
    options: &InitOptions,
    homography_rms: &[f64],
    closed: &mut ClosedFormStart,
) {
    let n_points = data.point_count() as f64;
    // The refined closed form must also be the lowest basin at the scale of
    // its own error: J at 0.5, 0.7, 1.4 and 2 × its f (its centre) and at its
    // f with the centre at (0, 0), on the subset, none below half its cost.
    // The check is skipped when the refined closed form already explains the
    // measured points better than a free homography per image does (image-
    // plane RMS at most the median homography RMS): a basin whose cost is
    // twice the global minimum's cannot.
    let explains_data = |p: &Profile| {
        let mut rms = homography_rms.to_vec();
        rms.sort_by(f64::total_cmp);
        let median = rms.get(rms.len() / 2).copied().unwrap_or(0.0);
        crate::problem::calibration_problem::total_cost(
            data,
            CostKind::Image,
            None,
            &(&p.model).into(),
            &p.poses,
        )
        .map(|c| (c / n_points).sqrt() <= median)
        .unwrap_or(false)
    };
    let well_fitted = closed.profile.as_ref().is_some_and(explains_data);
    if let Some((f, cx, cy, here)) = closed
        .candidate
        .filter(|_| options.refine_start && !well_fitted)
    {
        let subset = problem.subset(CHECK_IMAGES);
        let scale = subset.data.point_count() as f64 / problem.data.point_count() as f64;
        let here = here * scale;
        let mut best = (f, (cx, cy), f64::INFINITY);
        let trials = NEIGHBOUR_FACTORS
            .iter()
            .map(|k| (k * f, cx, cy))
            .chain([(f, 0.0, 0.0)]);
        for (ft, x, y) in trials {
            let c = subset.cost_or_inf(ft, x, y, Precision::Coarse);
            if c < best.2 {
                best = (ft, (x, y), c);
            }
        }
        if best.2 < 0.5 * here {
            closed.rejection = Some(format!(
                "closed-form start f = {f:.4} mm, centre ({cx:.3}, {cy:.3}) mm is not the lowest \
                 basin of the template-plane error: f = {:.4} mm, centre ({:.3}, {:.3}) mm lowers \
                 it from {here:.4e} to {:.4e} mm²",
                best.0, best.1 .0, best.1 .1, best.2
            ));
            closed.candidate = None;
            closed.profile = None;
        }
    }
}

/// The searched interval of `f` (mm) and its number of grid points.
fn search_range(options: &InitOptions) -> (f64, f64, usize) {
    match options.focal_guess {
        Some(g) => (0.5 * g, 2.0 * g, 13),
        None => (1.0, 1000.0, 41),
    }
}

/// Step 6, the focal search, when the closed form gives no plausible candidate
/// (or is not wanted): an error when the search is off.
fn focal_search(
    problem: &Problem,
    options: &InitOptions,
    geometry: &PsdGeometry,
    closed: &ClosedFormStart,
) -> Result<Option<FocalSearchReport>, CalibError> {
    // On large sets it runs on at most SEARCH_IMAGES images spread over the
    // set: f is a global quantity, and the start only needs to fall in the
    // right basin.
    let (s_lo, s_hi, s_n) = search_range(options);
    let mut search: Option<FocalSearchReport> = None;
    if closed.candidate.is_none() && !options.search_fallback {
        return Err(CalibError::Degenerate {
            reason: format!(
                "no plausible closed-form start ({}) and the focal search is off",
                closed.rejection.clone().unwrap_or_default()
            ),
        });
    }
    if closed.candidate.is_none() {
        let subset = problem.subset(SEARCH_IMAGES);
        let mut centres = vec![(0.0, 0.0, false)];
        if let Some(sol) = closed
            .solution
            .filter(|s| s.f_squared > 0.0 && on_area(geometry, s.cx, s.cy))
        {
            centres.push((sol.cx, sol.cy, true));
        }
        let mut evaluations = 0;
        for (cx, cy, from_cf) in centres {
            if let Some(mut rep) = subset.search(s_lo, s_hi, s_n, cx, cy) {
                evaluations += rep.evaluations;
                rep.centre_from_closed_form = from_cf;
                if search.as_ref().is_none_or(|s| rep.cost < s.cost) {
                    search = Some(rep);
                }
            }
        }
        if let Some(s) = search.as_mut() {
            s.evaluations = evaluations;
        }
    }
    Ok(search)
}

/// The route and its intrinsics `(f, cx, cy)`: the closed form when it is
/// a candidate, else the search's best.
fn choose_route(
    options: &InitOptions,
    closed: &ClosedFormStart,
    search: Option<FocalSearchReport>,
) -> Result<(InitRoute, f64, f64, f64), CalibError> {
    let (s_lo, s_hi, _) = search_range(options);
    let searched_route = if options.focal_guess.is_some() {
        InitRoute::FocalGuess
    } else {
        InitRoute::FocalSearch
    };
    match (closed.candidate, search) {
        (Some((f, cx, cy, _)), _) => Ok((InitRoute::ClosedForm, f, cx, cy)),
        (None, Some(s)) => Ok((searched_route, s.f, s.cx, s.cy)),
        (None, None) => Err(CalibError::Degenerate {
            reason: format!(
                "no focal length in [{s_lo}, {s_hi}] mm puts every template pose in front of \
                 the sensor (closed form: {})",
                closed.rejection.clone().unwrap_or_default()
            ),
        }),
    }
}

/// Step 7, the start at the route's intrinsics: the refined closed form (or the
/// paper's unrefined start), else `J`'s minimiser at `(f, cx, cy)`.
fn starting_profile(
    problem: &Problem,
    options: &InitOptions,
    route: InitRoute,
    closed: &mut ClosedFormStart,
    (f, cx, cy): (f64, f64, f64),
) -> Result<Profile, CalibError> {
    let start = match (route, closed.candidate) {
        (InitRoute::ClosedForm, Some(_)) if !options.refine_start => problem
            .plain_start(f, cx, cy)
            .ok()
            .filter(|p| p.cost.is_finite())
            .or(closed.profile.take()),
        (InitRoute::ClosedForm, Some(_)) => closed.profile.take(),
        _ => None,
    };
    match start {
        Some(p) => Ok(p),
        None => problem.profile(f, cx, cy, Precision::Fine),
    }
}

/// Step 7: after a search, the check that `f` is determined at all: with every
/// template pose parallel to the sensor the profile is flat (to rounding)
/// in `f`. With noise, the covariance of the refined fit judges instead
/// ([`mod@crate::calibrate`]). A neighbour lower than the start by more
/// than the flat-profile tolerance means the search stopped at its
/// interval's edge short of the minimum: the focal length lies outside the
/// interval ([`CalibError::FocalOutsideSearch`], naming `--focal-guess` when
/// it set the interval). Returns the focal sensitivity.
fn focal_sensitivity(
    data: &CalibrationData,
    problem: &Problem,
    options: &InitOptions,
    start: &Profile,
    (f, cx, cy): (f64, f64, f64),
) -> Result<f64, CalibError> {
    let (half, double) = (
        problem.cost_or_inf(0.5 * f, cx, cy, Precision::Fine),
        problem.cost_or_inf(2.0 * f, cx, cy, Precision::Fine),
    );
    let (better_f, neighbour) = if double <= half {
        (2.0 * f, double)
    } else {
        (0.5 * f, half)
    };
    let increase = neighbour - start.cost;
    if -increase > FLAT_PROFILE * start.cost + problem.floor {
        let (lo, hi, _) = search_range(options);
        return Err(CalibError::FocalOutsideSearch {
            guess: options.focal_guess,
            lo,
            hi,
            f,
            cost: start.cost,
            better_f,
            better_cost: neighbour,
        });
    }
    let dof = (2 * data.point_count())
        .saturating_sub(6 * data.images.len() + 4)
        .max(1) as f64;
    let variance = start.cost / dof;
    let focal_sensitivity = if variance > 0.0 {
        increase / variance
    } else {
        f64::INFINITY
    };
    if increase <= FLAT_PROFILE * start.cost + problem.floor {
        return Err(CalibError::Degenerate {
            reason: format!(
                "the focal length is not determined: halving or doubling it (from f = {f:.4} mm) \
                 changes the template-plane error by only {increase:.3e} mm² — the template \
                 poses are (nearly) all parallel to the sensor; tilt the template 10°–40° in \
                 several directions"
            ),
        });
    }
    Ok(focal_sensitivity)
}
