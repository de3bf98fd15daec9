//! The fit statistics of a calibration (docs/model.md §4.6): the paper's
//! *residual* (sum over every point of the squared template-plane error, mm²),
//! the RMS template-plane and image-plane errors, each image's RMS, the worst
//! points, and — under a robust loss — the points it down-weighted.
//!
//! For a point `m_ij` of LED `j` in image `i`:
//! template-plane error `e_t = ‖back_project(θ, pose_i, m_ij) − (X_j, Y_j)‖`
//! (mm on the template); image-plane error
//! `e_m = ‖project(θ, pose_i, X_j, Y_j) − m_ij‖` (mm on the sensor).
//! RMS values are `sqrt(mean(e²))` over points.

use psdcal_model::{Model, Pose};
use serde::Serialize;

use crate::data::CalibrationData;
use crate::problem::calibration_problem::{CalibrationProblem, FitState};
use psdcal_model::CostKind;
use psdcal_solver::solver::RobustLoss;

/// How many of the worst points a report lists.
pub const WORST_POINTS: usize = 10;

/// The errors of one point.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointError {
    /// Image id.
    pub image: String,
    /// LED index in the template.
    pub led: usize,
    /// Template-plane error, mm.
    pub template_mm: f64,
    /// Image-plane error, mm (`None` where the point cannot be reprojected).
    pub image_mm: Option<f64>,
}

/// The errors of one image.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImageStats {
    /// Image id.
    pub id: String,
    /// Points used.
    pub points: usize,
    /// RMS template-plane error, mm.
    pub rms_template_mm: f64,
    /// RMS image-plane error, mm.
    pub rms_image_mm: f64,
}

/// Fit statistics over the whole data set.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitStatistics {
    /// Sum of squared template-plane errors, mm² (the paper's residual).
    pub residual_mm2: f64,
    /// RMS template-plane error, mm.
    pub rms_template_mm: f64,
    /// RMS image-plane error, mm.
    pub rms_image_mm: f64,
    /// Points used.
    pub points: usize,
    /// Images used.
    pub images: usize,
    /// Per image.
    pub per_image: Vec<ImageStats>,
    /// The largest template-plane errors, worst first.
    pub worst_points: Vec<PointError>,
    /// Points whose robust weight fell below 1/2 (outliers), worst first;
    /// empty without a robust loss.
    pub outliers: Vec<PointError>,
    /// Points that could not be reprojected onto the sensor (outside the
    /// model's valid region); they count in neither image-plane figure.
    pub unprojectable: usize,
}

/// Per point: (template error, image error, image index, point index);
/// the ids are cloned only for the points reported.
type Scored = (f64, Option<f64>, usize, usize);

/// Computes the fit statistics of `(model, poses)` on `data` (the points
/// recomputed from the amplitudes when the model owns the gains). `cost`
/// and `robust` say what was minimised (to flag outliers in the right units).
pub fn fit_statistics(
    data: &CalibrationData,
    model: &Model,
    poses: &[Pose],
    cost: CostKind,
    robust: Option<RobustLoss>,
) -> FitStatistics {
    let state = FitState {
        model: model.clone(),
        poses: poses.to_vec(),
    };
    let problems = [CostKind::Template, CostKind::Image]
        .map(|kind| CalibrationProblem::new(data, kind, model, &[], None));
    let [Ok(template), Ok(image_plane)] = problems else {
        // Only a gains stage without amplitudes fails here: nothing to measure.
        return FitStatistics::empty(data);
    };
    let mut all: Vec<Scored> = Vec::with_capacity(data.point_count());
    let mut outliers: Vec<Scored> = Vec::new();
    let mut per_image = Vec::with_capacity(data.images.len());
    let (mut sum_t, mut sum_m, mut n_m, mut unprojectable) = (0.0, 0.0, 0usize, 0usize);
    for (i, image) in data.images.iter().enumerate() {
        let (mut img_t, mut img_m, mut img_n_m) = (0.0, 0.0, 0usize);
        let rotation = state.poses[i].rotation();
        for k in 0..image.points.len() {
            let e_t = template
                .residual_using(&state, i, k, &rotation)
                .map(|r| r.norm())
                .unwrap_or(f64::INFINITY);
            let e_m = image_plane
                .residual_using(&state, i, k, &rotation)
                .ok()
                .map(|r| r.norm());
            img_t += e_t * e_t;
            match e_m {
                Some(e) => {
                    img_m += e * e;
                    img_n_m += 1;
                }
                None => unprojectable += 1,
            }
            if let Some(loss) = robust {
                let e = match cost {
                    CostKind::Template => Some(e_t),
                    CostKind::Image => e_m,
                };
                if e.is_none_or(|e| loss.weight(e * e) < 0.5) {
                    outliers.push((e_t, e_m, i, k));
                }
            }
            all.push((e_t, e_m, i, k));
        }
        let n = image.points.len().max(1) as f64;
        per_image.push(ImageStats {
            id: image.id.clone(),
            points: image.points.len(),
            rms_template_mm: (img_t / n).sqrt(),
            rms_image_mm: if img_n_m > 0 {
                (img_m / img_n_m as f64).sqrt()
            } else {
                f64::INFINITY
            },
        });
        sum_t += img_t;
        sum_m += img_m;
        n_m += img_n_m;
    }
    let points = data.point_count();
    let (all, outliers) = worst_named(data, all, outliers);
    FitStatistics {
        residual_mm2: sum_t,
        rms_template_mm: (sum_t / points.max(1) as f64).sqrt(),
        rms_image_mm: if n_m > 0 {
            (sum_m / n_m as f64).sqrt()
        } else {
            f64::INFINITY
        },
        points,
        images: data.images.len(),
        per_image,
        worst_points: all,
        outliers,
        unprojectable,
    }
}

/// The [`WORST_POINTS`] largest template-plane errors of `all` and every
/// outlier, each worst first, with their image ids and LEDs.
fn worst_named(
    data: &CalibrationData,
    mut all: Vec<Scored>,
    mut outliers: Vec<Scored>,
) -> (Vec<PointError>, Vec<PointError>) {
    let worst_first = |list: &mut Vec<Scored>| {
        list.sort_by(|a, b| b.0.total_cmp(&a.0));
    };
    let named = |list: &[Scored]| -> Vec<PointError> {
        list.iter()
            .map(|&(template_mm, image_mm, i, k)| PointError {
                image: data.images[i].id.clone(),
                led: data.images[i].points[k].led,
                template_mm,
                image_mm,
            })
            .collect()
    };
    worst_first(&mut all);
    all.truncate(WORST_POINTS);
    worst_first(&mut outliers);
    (named(&all), named(&outliers))
}

impl FitStatistics {
    /// Statistics of nothing (no point could be evaluated).
    fn empty(data: &CalibrationData) -> Self {
        Self {
            residual_mm2: f64::INFINITY,
            rms_template_mm: f64::INFINITY,
            rms_image_mm: f64::INFINITY,
            points: data.point_count(),
            images: data.images.len(),
            per_image: Vec::new(),
            worst_points: Vec::new(),
            outliers: Vec::new(),
            unprojectable: data.point_count(),
        }
    }
}
