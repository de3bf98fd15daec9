//! The surveyed calibration's steps (the method is documented on
//! [`crate::surveyed`]): the input's checks, the DLT start with its
//! preliminary `k1`, the refinement from competing starts, and the
//! covariance with survey noise, `Cov(x) = σ_m² S⁻¹ + σ_s² S⁻¹ G Gᵀ S⁻¹`.

use nalgebra::{DMatrix, SMatrix, Vector2, Vector3};
use psdcal_model::{Model, Param, ParameterCovariance, Pose, SensorModel};
use psdcal_solver::solver::{self, SolverOptions, SolverReport};

use crate::diagnose::residual_structure::DiagnosticReport;
use crate::surveyed::checks::check_surveyed;
use crate::surveyed::input::{SurveyedData, SurveyedOptions};
use crate::surveyed::problem::{dense_jacobians, SurveyedProblem, SurveyedState};
use crate::surveyed::projection_dlt::relative_reprojection;
use crate::surveyed::projection_dlt::{
    decompose_projection, dlt_projection, flatness, MIN_SURVEYED_POINTS,
};
use crate::uncertainty::linearity::LinearityCheck;
use crate::warning::FitWarning;
use crate::CalibError;

/// Smallest ratio of the point cloud's third to first principal spread
/// (its flatness) accepted by the DLT start in a single image.
pub const MIN_DEPTH_RATIO: f64 = 0.02;

/// A finished calibration from surveyed points.
#[derive(Debug, Clone, PartialEq)]
pub struct SurveyedCalibration {
    /// The estimated model.
    pub model: Model,
    /// Per image, `sensor_from_template` (the template frame is the survey's:
    /// for an in-situ calibration, `sensor_from_room`).
    pub poses: Vec<Pose>,
    /// The freed model parameters' covariance (survey noise included).
    pub covariance: ParameterCovariance,
    /// Per image, the 6 × 6 covariance of the pose `(rvec, t)`.
    pub pose_covariances: Vec<SMatrix<f64, 6, 6>>,
    /// The measured point's variance per coordinate estimated from the
    /// residuals (mm²), the survey's share removed.
    pub point_variance: f64,
    /// Cost `Σ ‖r‖²`, mm² on the sensor.
    pub cost: f64,
    /// RMS image-plane error, mm.
    pub rms_image_mm: f64,
    /// Per image, its RMS image-plane error, mm.
    pub rms_per_image_mm: Vec<f64>,
    /// Points used.
    pub points: usize,
    /// Degrees of freedom `2n − p`.
    pub dof: usize,
    /// The DLT start's `(f, cx, cy)` (`None` for a refinement from a given start).
    pub start: Option<[f64; 3]>,
    /// The solver's report.
    pub report: SolverReport,
    /// What the user should know (residuals smaller than the survey σ
    /// predicts, a poorly determined parameter).
    pub warnings: Vec<FitWarning>,
    /// The diagnostics (calibration.json's `diagnostics`) and their
    /// statistics ([`crate::surveyed_checks`]).
    pub diagnostics: DiagnosticReport,
    /// The cost at ±3σ of each freed parameter ([`crate::surveyed_checks`]).
    pub linearity: LinearityCheck,
}

/// The whole calibration: checks, DLT start, refinement, covariance.
pub fn calibrate_surveyed(
    data: &SurveyedData,
    options: &SurveyedOptions,
) -> Result<SurveyedCalibration, CalibError> {
    check(data, options)?;
    let (start_model, poses) = dlt_start(data, options, 0.0)?;
    let start = [
        start_model.intrinsics.f,
        start_model.intrinsics.cx,
        start_model.intrinsics.cy,
    ];
    let mut refined = refine_from_start(data, &start_model, &poses, options)?;
    if options.free.contains(&Param::K1) {
        let k1 = preliminary_k1(data);
        if k1 != 0.0 {
            if let Ok((m, p)) = dlt_start(data, options, k1) {
                if let Ok(r) = refine_from_start(data, &m, &p, options) {
                    if r.report.termination.converged() && r.cost < refined.cost {
                        refined = r;
                    }
                }
            }
        }
    }
    let mut result = finish(data, options, refined)?;
    result.start = Some(start);
    Ok(result)
}

/// The refinement from the DLT start: the model freed at once, and staged
/// (the pinhole's `f, cx, cy` and the poses first, distortion held at zero,
/// then everything freed); the converged candidate with the lower cost
/// wins (a start far from a strong distortion can end in a local minimum
/// that the staged route avoids, and the other way round); both from the
/// DLT's principal point and from the sensor's centre.
fn refine_from_start(
    data: &SurveyedData,
    start: &SensorModel,
    poses: &[Pose],
    options: &SurveyedOptions,
) -> Result<RefinedSurveyed, CalibError> {
    let mut best = refine_both_ways(data, start, poses, options);
    // Strong distortion pulls the DLT's principal point away: the sensor's
    // centre competes as a start.
    let frees_centre = options.free.contains(&Param::Cx) || options.free.contains(&Param::Cy);
    if frees_centre {
        let mut centred = *start;
        centred.intrinsics.cx = 0.0;
        centred.intrinsics.cy = 0.0;
        let other = refine_both_ways(data, &centred, poses, options);
        best = match (best, other) {
            (Ok(a), Ok(b)) if b.cost < a.cost => Ok(b),
            (Err(_), Ok(b)) => Ok(b),
            (a, _) => a,
        };
    }
    best
}

fn refine_both_ways(
    data: &SurveyedData,
    start: &SensorModel,
    poses: &[Pose],
    options: &SurveyedOptions,
) -> Result<RefinedSurveyed, CalibError> {
    let direct = refine_surveyed(data, Model::standard(start), poses, options);
    let pinhole: Vec<Param> = options
        .free
        .iter()
        .copied()
        .filter(|p| matches!(p, Param::F | Param::Cx | Param::Cy))
        .collect();
    let staged = (pinhole.len() < options.free.len()).then(|| {
        let first = SurveyedOptions {
            free: pinhole,
            ..options.clone()
        };
        refine_surveyed(data, Model::standard(start), poses, &first)
            .and_then(|r| refine_surveyed(data, r.state.model, &r.state.poses, options))
    });
    let usable = |r: &RefinedSurveyed| r.report.termination.converged() && r.cost.is_finite();
    match (direct, staged) {
        (Ok(a), Some(Ok(b))) if usable(&b) && (!usable(&a) || b.cost < a.cost) => Ok(b),
        (Ok(a), _) => Ok(a),
        (Err(_), Some(Ok(b))) => Ok(b),
        (Err(e), _) => Err(e),
    }
}

/// A refinement's answer.
#[derive(Debug, Clone)]
pub struct RefinedSurveyed {
    /// The state at the end.
    pub state: SurveyedState,
    /// Its cost.
    pub cost: f64,
    /// The solver's report.
    pub report: SolverReport,
}

/// Refines `start` and `poses` (any start: the DLT's, or the truth for a
/// comparison) over the freed parameters of `options`.
pub fn refine_surveyed(
    data: &SurveyedData,
    start: Model,
    poses: &[Pose],
    options: &SurveyedOptions,
) -> Result<RefinedSurveyed, CalibError> {
    let problem = SurveyedProblem::new(data, &start, &options.free)?;
    let points = data.images.iter().map(|i| i.points.len()).sum::<usize>() as f64;
    let settings = SolverOptions {
        max_iterations: options.max_iterations,
        cost_tolerance: 1e-12,
        step_tolerance: 1e-12,
        initial_lambda: 1e-3,
        exact_cost: psdcal_model::fit::EXACT_FIT_MEAN_SQUARE_MM2 * points,
        step_floor: 1e-26 * points,
        robust: None,
    };
    let state = SurveyedState {
        model: start,
        poses: poses.to_vec(),
    };
    let solution = solver::solve(&problem, state, &settings)?;
    Ok(RefinedSurveyed {
        state: solution.state,
        cost: solution.cost,
        report: solution.report,
    })
}

/// The input's checks, each failure with what to change.
fn check(data: &SurveyedData, options: &SurveyedOptions) -> Result<(), CalibError> {
    if !(options.survey_sigma_mm.is_finite() && options.survey_sigma_mm >= 0.0) {
        return Err(CalibError::InvalidInput {
            reason: format!(
                "the survey's σ must be finite and ≥ 0 mm (got {})",
                options.survey_sigma_mm
            ),
        });
    }
    if data.images.is_empty() {
        return Err(CalibError::TooFewImages {
            usable: 0,
            needed: 1,
        });
    }
    if data
        .points
        .iter()
        .any(|p| !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()))
    {
        return Err(CalibError::InvalidInput {
            reason: "a surveyed point has a non-finite coordinate".into(),
        });
    }
    for image in &data.images {
        let n = image.points.len();
        if n < MIN_SURVEYED_POINTS {
            return Err(CalibError::Degenerate {
                reason: format!(
                    "image '{}' sees {n} surveyed point(s); the 3-D start needs at least {} \
                     (not all on one plane) in every image: add emitters in its field of view \
                     or drop the image",
                    image.id, MIN_SURVEYED_POINTS
                ),
            });
        }
        if let Some(o) = image.points.iter().find(|o| o.led >= data.points.len()) {
            return Err(CalibError::UnknownLed {
                led: o.led,
                template_len: data.points.len(),
            });
        }
        let cloud: Vec<Vector3<f64>> = image.points.iter().map(|o| data.points[o.led]).collect();
        let ratio = flatness(&cloud);
        if ratio < MIN_DEPTH_RATIO {
            return Err(CalibError::Degenerate {
                reason: format!(
                    "the surveyed points image '{}' sees are (nearly) coplanar (their spread off \
                     their best plane is {:.2} % of their extent; at least {:.0} % needed): one \
                     image cannot calibrate from a plane — place emitters at different depths \
                     (walls, floor, ceiling, stands), or calibrate with a planar template in \
                     several poses (psdcal calibrate)",
                    image.id,
                    100.0 * ratio,
                    100.0 * MIN_DEPTH_RATIO
                ),
            });
        }
    }
    Ok(())
}

/// The preliminary radial correction of the 3-D start: the `k1` (about
/// the sensor's centre) whose corrected points the per-image DLTs explain
/// best — the sum over images of the DLT's reprojection error relative to
/// the spread of the corrected points (scale-free) — over a grid of
/// `k1 r_c² ∈ [−0.4, 0.8]` in steps of 0.05 (`r_c` the distance from the
/// centre to the active area's corner).
pub fn preliminary_k1(data: &SurveyedData) -> f64 {
    let rc2 = 0.25 * (data.geometry.lx.powi(2) + data.geometry.ly.powi(2));
    let mut best = (f64::INFINITY, 0.0);
    for step in -8..=16 {
        let k1 = 0.05 * f64::from(step) / rc2;
        let mut model = SensorModel::pinhole(1.0, 0.0, 0.0);
        model.distortion.k1 = k1;
        let model = Model::standard(&model);
        let mut score = 0.0;
        for image in &data.images {
            let pts: Vec<Vector3<f64>> = image.points.iter().map(|o| data.points[o.led]).collect();
            let ideal: Vec<Vector2<f64>> = image
                .points
                .iter()
                .map(|o| model.ideal(&o.measured))
                .collect();
            score += match dlt_projection(&pts, &ideal) {
                Some(p) => relative_reprojection(&p, &pts, &ideal),
                None => f64::INFINITY,
            };
        }
        if score < best.0 {
            best = (score, k1);
        }
    }
    best.1
}

fn dlt_start(
    data: &SurveyedData,
    options: &SurveyedOptions,
    k1: f64,
) -> Result<(SensorModel, Vec<Pose>), CalibError> {
    let mut radial = SensorModel::pinhole(1.0, 0.0, 0.0);
    radial.distortion.k1 = k1;
    let radial = Model::standard(&radial);
    let mut fs = Vec::new();
    let mut cxs = Vec::new();
    let mut cys = Vec::new();
    let mut poses = Vec::new();
    for image in &data.images {
        let pts: Vec<Vector3<f64>> = image.points.iter().map(|o| data.points[o.led]).collect();
        let ms: Vec<Vector2<f64>> = image
            .points
            .iter()
            .map(|o| radial.ideal(&o.measured))
            .collect();
        let (k, pose) = dlt_projection(&pts, &ms)
            .and_then(|p| decompose_projection(&p))
            .ok_or_else(|| CalibError::Degenerate {
                reason: format!(
                    "the 3-D start failed on image '{}' (its points and measurements admit no \
                     camera): check that the points' identifiers match the survey and that \
                     they span depth",
                    image.id
                ),
            })?;
        fs.push(0.5 * (k[(0, 0)] + k[(1, 1)]));
        cxs.push(k[(0, 2)]);
        cys.push(k[(1, 2)]);
        poses.push(pose);
    }
    let mut model = options.base;
    let free = |p: Param| options.free.contains(&p);
    if free(Param::F) {
        model.intrinsics.f = median(&mut fs);
    }
    if free(Param::Cx) {
        model.intrinsics.cx = median(&mut cxs);
    }
    if free(Param::Cy) {
        model.intrinsics.cy = median(&mut cys);
    }
    if !(model.intrinsics.f.is_finite() && model.intrinsics.f > 0.0) {
        return Err(CalibError::Degenerate {
            reason: format!(
                "the 3-D start gives focal length {} mm: the points may be mislabelled or too \
                 close to one plane",
                model.intrinsics.f
            ),
        });
    }
    for p in [
        Param::K1,
        Param::K2,
        Param::K3,
        Param::P1,
        Param::P2,
        Param::L1,
        Param::L2,
    ] {
        if free(p) {
            model.set(p, 0.0);
        }
    }
    if free(Param::K1) {
        model.distortion.k1 = k1;
    }
    Ok((model, poses))
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The covariance of `x = (θ_free, poses)` with the survey noise
/// (module documentation) and σ_m².
pub fn survey_covariance(
    j: &DMatrix<f64>,
    cost: f64,
    jp: &[(usize, SMatrix<f64, 2, 3>)],
    n_points: usize,
    survey_sigma_mm: f64,
) -> Option<(DMatrix<f64>, f64, f64)> {
    let (rows, cols) = j.shape();
    let dof = rows.checked_sub(cols).filter(|d| *d > 0)?;
    let s = j.transpose() * j;
    let s_inv = s.clone().cholesky()?.inverse();
    // G = Jᵀ J_P, one 3-column block per surveyed point.
    let mut g = DMatrix::<f64>::zeros(cols, 3 * n_points);
    let mut trace_jp = 0.0;
    for (obs, (point, dp)) in jp.iter().enumerate() {
        let jrows = j.rows(2 * obs, 2);
        let contribution = jrows.transpose() * dp;
        let mut block = g.columns_mut(3 * point, 3);
        block += contribution;
        trace_jp += dp.norm_squared();
    }
    let sg = &s_inv * &g;
    let trace_h = (g.transpose() * &sg).trace();
    let sigma_s2 = survey_sigma_mm * survey_sigma_mm;
    let share = sigma_s2 * (trace_jp - trace_h);
    let sigma_m2 = (cost - share).max(0.0) / dof as f64;
    let cov = &s_inv * sigma_m2 + (&sg * sg.transpose()) * sigma_s2;
    Some((cov, sigma_m2, share))
}

/// Covariance, statistics and warnings of a refinement.
fn finish(
    data: &SurveyedData,
    options: &SurveyedOptions,
    refined: RefinedSurveyed,
) -> Result<SurveyedCalibration, CalibError> {
    if !refined.report.termination.converged() {
        return Err(CalibError::NotConverged {
            reason: format!(
                "{} iterations without meeting a stopping criterion (cost {:.6e}); add \
                 emitters spread over the field of view and in depth",
                refined.report.iterations, refined.cost
            ),
        });
    }
    let state = &refined.state;
    let (j, r, jp) = dense_jacobians(data, state, &options.free)?;
    let (cov, sigma_m2, share) = survey_covariance(
        &j,
        refined.cost,
        &jp,
        data.points.len(),
        options.survey_sigma_mm,
    )
    .ok_or_else(|| CalibError::Degenerate {
        reason: format!(
            "the parameters are not determined by these points ({} residuals for {} unknowns, \
             or a singular geometry): add emitters spread over the field of view and in depth, \
             or orientations",
            j.nrows(),
            j.ncols()
        ),
    })?;
    let p = options.free.len();
    let names: Vec<String> = options.free.iter().map(|q| q.name().to_string()).collect();
    let rows: Vec<Vec<f64>> = (0..p)
        .map(|a| (0..p).map(|b| cov[(a, b)]).collect())
        .collect();
    let covariance =
        ParameterCovariance::from_named(&names, &rows).map_err(|e| CalibError::Numerical {
            stage: "surveyed covariance",
            reason: e.to_string(),
        })?;
    let pose_covariances = (0..data.images.len())
        .map(|i| cov.fixed_view::<6, 6>(p + 6 * i, p + 6 * i).into_owned())
        .collect();
    let mut warnings = Vec::new();
    if options.survey_sigma_mm > 0.0 && refined.cost < share {
        warnings.push(FitWarning::SurveyBetterThanStated {
            residual_mm2: refined.cost,
            survey_sigma_mm: options.survey_sigma_mm,
            predicted_mm2: share,
        });
    }
    if let Some(sd) = covariance.std("f") {
        let f = state.model.get("f").unwrap_or(f64::NAN);
        if sd > 0.2 * f {
            return Err(CalibError::Degenerate {
                reason: format!(
                    "the focal length is not determined (f = {f:.4} ± {sd:.4} mm): add \
                     emitters at different depths and across the whole field of view"
                ),
            });
        }
    }
    let mut rms_per_image = Vec::new();
    let mut offset = 0;
    for image in &data.images {
        let len = 2 * image.points.len();
        let ss = r.rows(offset, len).norm_squared();
        rms_per_image.push((ss / image.points.len() as f64).sqrt());
        offset += len;
    }
    let points = r.len() / 2;
    let checks = check_surveyed(data, options, state, &covariance)?;
    Ok(SurveyedCalibration {
        model: state.model.clone(),
        poses: state.poses.clone(),
        covariance,
        pose_covariances,
        point_variance: sigma_m2,
        cost: refined.cost,
        rms_image_mm: (r.norm_squared() / points as f64).sqrt(),
        rms_per_image_mm: rms_per_image,
        points,
        dof: j.nrows() - j.ncols(),
        start: None,
        report: refined.report,
        warnings,
        diagnostics: checks.report,
        linearity: checks.linearity,
    })
}

/// `finish` for a refinement from any start (the comparison with a fit
/// started from the truth).
pub fn finish_refined(
    data: &SurveyedData,
    options: &SurveyedOptions,
    refined: RefinedSurveyed,
) -> Result<SurveyedCalibration, CalibError> {
    finish(data, options, refined)
}
