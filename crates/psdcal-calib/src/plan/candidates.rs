//! Candidate template poses for a plan (docs/model.md §8.6), drawn from a
//! seed (ChaCha8) within the mount's ranges.
//!
//! A candidate aims the template's centre (the mean of its LEDs) at a point
//! `a` drawn uniformly on the active area: the centre lies at distance `s`
//! along the ray of `a` (`s` log-uniform in the distance range). The
//! template is turned by a roll about its normal (uniform), then tilted by
//! `τ` (uniform in `[0, τ_max]`) about an in-plane axis (uniform direction):
//! `R = R_tilt R_roll`, so `τ` is the angle between the template's normal
//! and the optical axis. A candidate is kept when every LED's measured point
//! through the nominal model lies inside the active area by the margin
//! and the template faces the sensor.
//!
//! Without a distance range the distances run from half to ten times
//! `s₀ = f ρ_t / h` (`ρ_t` the template's radius about its centre, `h` the
//! smaller half side of the active area less the margin): below about `s₀` the
//! template no longer fits face-on, beyond `10 s₀` it covers a tenth of
//! the area across.

use nalgebra::{Vector2, Vector3};
use psdcal_model::Pose;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::plan::information::PlanSetup;
use crate::CalibError;

/// Largest tilt a plan accepts, degrees (beyond it the LEDs are seen
/// nearly edge-on).
pub const MAX_TILT_DEG: f64 = 80.0;

/// Draws per wanted candidate before giving up.
const DRAWS_PER_CANDIDATE: usize = 200;

/// The mount's ranges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseRanges {
    /// Distance of the template's centre from the sensor, mm (`None`: any
    /// at which the template stays on the active area).
    pub distance_mm: Option<(f64, f64)>,
    /// Largest tilt of the template's normal from the optical axis, rad.
    pub tilt_max: f64,
    /// Margin kept between every LED's point and the active area's edge, mm.
    pub margin_mm: f64,
}

impl Default for PoseRanges {
    /// Any distance, tilt up to 45°, 0.2 mm margin.
    fn default() -> Self {
        Self {
            distance_mm: None,
            tilt_max: 45f64.to_radians(),
            margin_mm: 0.2,
        }
    }
}

/// One admissible pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// `sensor_from_template`.
    pub pose: Pose,
    /// Distance of the template's centre, mm.
    pub distance_mm: f64,
    /// Tilt of the template's normal from the optical axis, rad.
    pub tilt: f64,
}

/// The template's centre and radius about it.
fn centre_and_radius(template: &[Vector2<f64>]) -> (Vector2<f64>, f64) {
    let centre = template.iter().sum::<Vector2<f64>>() / template.len().max(1) as f64;
    let radius = template
        .iter()
        .map(|p| (p - centre).norm())
        .fold(0.0, f64::max);
    (centre, radius)
}

/// The distance range used: the given one, or the default (module
/// documentation). Checks the ranges and says what to change.
pub fn distance_range(setup: &PlanSetup, ranges: &PoseRanges) -> Result<(f64, f64), CalibError> {
    let bad = |reason: String| Err(CalibError::InvalidInput { reason });
    if !(ranges.tilt_max.is_finite()
        && (0.0..=MAX_TILT_DEG.to_radians()).contains(&ranges.tilt_max))
    {
        return bad(format!(
            "--tilt-max {:.1}° is unreachable: the template must face the sensor; give a tilt between 0 and {MAX_TILT_DEG}°",
            ranges.tilt_max.to_degrees()
        ));
    }
    let h = 0.5 * setup.geometry.lx.min(setup.geometry.ly) - ranges.margin_mm;
    if !(ranges.margin_mm.is_finite() && ranges.margin_mm >= 0.0 && h > 0.0) {
        return bad(format!(
            "a margin of {} mm leaves no active area; use a smaller margin",
            ranges.margin_mm
        ));
    }
    let (_, radius) = centre_and_radius(&setup.template);
    let f = setup.model.get("f").unwrap_or(f64::NAN);
    let s0 = f * radius / h;
    match ranges.distance_mm {
        Some((lo, hi)) if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi >= lo) => bad(format!(
            "--distance {lo}:{hi} is not a range of positive distances MIN:MAX (mm)"
        )),
        Some((lo, hi)) if hi < 0.5 * s0 => bad(format!(
            "no pose at --distance {lo}:{hi} mm keeps the template on the active area: at {hi} mm \
             its image is about {:.1} mm across where the margin leaves {:.1} mm; allow distances up to at least {:.0} mm",
            2.0 * f * radius / hi,
            2.0 * h,
            s0
        )),
        Some(range) => Ok(range),
        None if s0.is_finite() && s0 > 0.0 => Ok((0.5 * s0, 10.0 * s0)),
        None => bad("the template's LEDs coincide: a plan needs a template of some size".into()),
    }
}

/// Draws `count` admissible candidates (module documentation); fewer when
/// the ranges leave too few (the caller decides whether that is enough).
pub fn draw_candidates(
    setup: &PlanSetup,
    ranges: &PoseRanges,
    count: usize,
    seed: u64,
) -> Result<Vec<Candidate>, CalibError> {
    let (lo, hi) = distance_range(setup, ranges)?;
    let (centre, _) = centre_and_radius(&setup.template);
    let hx = 0.5 * setup.geometry.lx - ranges.margin_mm;
    let hy = 0.5 * setup.geometry.ly - ranges.margin_mm;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(count);
    for _ in 0..count * DRAWS_PER_CANDIDATE {
        if out.len() == count {
            break;
        }
        let aim = Vector2::new(rng.random_range(-hx..hx), rng.random_range(-hy..hy));
        let distance = lo * (hi / lo).powf(rng.random_range(0.0..=1.0));
        let tilt = ranges.tilt_max * rng.random_range(0.0..=1.0);
        let axis = rng.random_range(0.0..std::f64::consts::TAU);
        let roll = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        let tilt_pose = Pose::new(
            Vector3::new(axis.cos(), axis.sin(), 0.0) * tilt,
            Vector3::zeros(),
        );
        let roll_pose = Pose::new(Vector3::new(0.0, 0.0, roll), Vector3::zeros());
        let rotation = tilt_pose.compose(&roll_pose);
        let ray = setup.model.ray(&aim);
        let direction = Vector3::new(ray.x, ray.y, 1.0).normalize();
        let t = direction * distance - rotation.rotation() * Vector3::new(centre.x, centre.y, 0.0);
        let pose = Pose::new(rotation.rvec, t);
        let normal = rotation.rotation().column(2).into_owned();
        if normal.dot(&direction).abs() < 0.2 {
            continue;
        }
        let inside = setup.template.iter().all(|xy| {
            pose.transform(&Vector3::new(xy.x, xy.y, 0.0)).z > 0.0
                && setup
                    .model
                    .project(&pose, xy)
                    .is_ok_and(|m| m.x.abs() <= hx && m.y.abs() <= hy)
        });
        if inside {
            out.push(Candidate {
                pose,
                distance_mm: distance,
                tilt,
            });
        }
    }
    Ok(out)
}
