//! In-situ calibration scenes (docs/model.md §8.4): a sensor mounted in a
//! room, IR emitters fixed at surveyed positions, one or several sensor
//! orientations (images).
//!
//! *Room*: a box `[0, W] × [0, D] × [0, H]` mm (5 × 4 × 2.6 m by default),
//! `z` up. *Mount*: a point within 0.3 m of one wall (drawn uniformly), at
//! height 1.5–2.4 m. *Orientation* k: the optical axis `z_s` aims at a point
//! of the room's central box (its middle 60 % on every axis), the first
//! orientation drawn there and the others panned from it by up to
//! `pan_fraction` of the half field of view about random axes; the roll is
//! uniform. The sensor's frame from its axes: `room_from_sensor =
//! [x_s y_s z_s | mount]` with `y_s = z_s × x_s`.
//! *Emitters*: uniform in the room (0.5 m or more from the sensor), kept
//! when their true impact falls inside the central `margin` of the active
//! area in the orientation they are assigned to (round robin); a scene
//! whose orientations do not each see at least [`MIN_SEEN`] emitters is
//! redrawn. *Measurements*: every emitter an orientation sees, its true
//! impact point (pinhole, then the lens's distortion) plus Gaussian noise σ_m
//! per coordinate. *Survey*: the positions given to the calibration are the
//! true ones plus Gaussian noise σ_s per coordinate.
//!
//! The SNR is mapped to σ_m as psdcal's robustness experiments do,
//! `σ_m = 0.4 µm · 10^((40 − SNR)/20)` (the sensor-plane noise the paper's
//! 40 dB residuals imply).
//!
//! [`InSituOptions::wide`] draws scenes far wider than the defaults (either
//! lens with `f` ±10 %, centre ±0.8 mm, `k1` ×0.5–1.5, 16–24 emitters, 1–3
//! orientations panned up to 60 % of the half field of view, σ_s 0.5–5 mm
//! log-uniform, 35–45 dB).

use nalgebra::{Matrix3, Unit, Vector2, Vector3};
use psdcal_model::{Model, Pose, PsdGeometry, SensorModel};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use crate::room::true_impact;
use crate::scenario::Lens;
use crate::SimError;

/// Fewest emitters every orientation must see.
pub const MIN_SEEN: usize = 8;
/// Most redraws of a scene.
const MAX_SCENE_DRAWS: usize = 200;

/// The point noise σ_m (mm) of an SNR (dB) (module documentation).
pub fn point_sigma_mm(snr_db: f64) -> f64 {
    4e-4 * 10f64.powf((40.0 - snr_db) / 20.0)
}

/// What a scene is drawn from.
#[derive(Debug, Clone, PartialEq)]
pub struct InSituOptions {
    /// The sensor's true model.
    pub truth: SensorModel,
    /// The PSD's active area.
    pub geometry: PsdGeometry,
    /// Room width, depth, height, mm.
    pub room_mm: [f64; 3],
    /// Number of emitters.
    pub emitters: usize,
    /// Number of sensor orientations (images).
    pub orientations: usize,
    /// Largest pan of the later orientations, fraction of the half field of view.
    pub pan_fraction: f64,
    /// SNR, dB (→ σ_m by [`point_sigma_mm`]).
    pub snr_db: f64,
    /// Survey σ per coordinate, mm.
    pub survey_sigma_mm: f64,
    /// Central fraction of the active area an emitter's impact must fall in.
    pub margin: f64,
}

impl Default for InSituOptions {
    /// Lens 2, a 5 × 4 × 2.6 m room, 20 emitters, one orientation, 40 dB,
    /// survey σ 2 mm.
    fn default() -> Self {
        Self {
            truth: SensorModel::paper_lens2(),
            geometry: PsdGeometry::default(),
            room_mm: [5000.0, 4000.0, 2600.0],
            emitters: 20,
            orientations: 1,
            pan_fraction: 0.4,
            snr_db: 40.0,
            survey_sigma_mm: 2.0,
            margin: 0.9,
        }
    }
}

impl InSituOptions {
    /// A wide draw (module documentation), from its own generator.
    pub fn wide(rng: &mut ChaCha8Rng) -> Self {
        let lens = if rng.random_bool(0.5) {
            Lens::One
        } else {
            Lens::Two
        };
        let mut truth = lens.model();
        truth.intrinsics.f *= rng.random_range(0.9..1.1);
        truth.intrinsics.cx = rng.random_range(-0.8..0.8);
        truth.intrinsics.cy = rng.random_range(-0.8..0.8);
        truth.distortion.k1 *= rng.random_range(0.5..1.5);
        Self {
            truth,
            emitters: rng.random_range(16..=24),
            orientations: rng.random_range(1..=3),
            pan_fraction: 0.6,
            snr_db: rng.random_range(35.0..45.0),
            survey_sigma_mm: rng.random_range(0.5f64.ln()..5f64.ln()).exp(),
            ..Self::default()
        }
    }
}

/// A drawn scene with its measurements.
#[derive(Debug, Clone, PartialEq)]
pub struct InSituScene {
    /// The options it was drawn with.
    pub options: InSituOptions,
    /// Each emitter's true position (room frame), mm.
    pub emitters: Vec<Vector3<f64>>,
    /// Each emitter's surveyed position (true + survey noise), mm.
    pub surveyed: Vec<Vector3<f64>>,
    /// Per orientation, the sensor's true `room_from_sensor`.
    pub room_from_sensor: Vec<Pose>,
    /// Per orientation, `(emitter, measured point)` for every emitter seen.
    pub observations: Vec<Vec<(usize, Vector2<f64>)>>,
    /// The point noise σ_m per coordinate, mm.
    pub point_sigma_mm: f64,
}

/// The pose whose optical axis runs from `mount` towards `aim`, rolled by
/// `roll` about it.
pub fn look_at(mount: &Vector3<f64>, aim: &Vector3<f64>, roll: f64) -> Option<Pose> {
    let z = (aim - mount).try_normalize(1e-9)?;
    let helper = if z.z.abs() < 0.9 {
        Vector3::z()
    } else {
        Vector3::x()
    };
    let x0 = helper.cross(&z).normalize();
    let x = nalgebra::Rotation3::from_axis_angle(&Unit::new_normalize(z), roll) * x0;
    let y = z.cross(&x);
    let r = Matrix3::from_columns(&[x, y, z]);
    Some(Pose::from_rotation(&r, *mount))
}

impl InSituScene {
    /// Draws a scene (module documentation).
    pub fn draw(options: &InSituOptions, rng: &mut ChaCha8Rng) -> Result<Self, SimError> {
        let o = options;
        if o.emitters == 0
            || o.orientations == 0
            || !(o.margin > 0.0 && o.margin <= 1.0)
            || o.room_mm.iter().any(|v| !(v.is_finite() && *v > 1000.0))
            || !(o.survey_sigma_mm.is_finite() && o.survey_sigma_mm >= 0.0)
            || !o.snr_db.is_finite()
        {
            return Err(SimError::Options(format!(
                "an in-situ scene needs ≥ 1 emitter ({}), ≥ 1 orientation ({}), a margin in \
                 (0, 1] ({}), room sides above 1 m ({:?}), a survey σ ≥ 0 ({}) and a finite SNR",
                o.emitters, o.orientations, o.margin, o.room_mm, o.survey_sigma_mm
            )));
        }
        for _ in 0..MAX_SCENE_DRAWS {
            if let Some(scene) = Self::try_draw(o, rng) {
                return Ok(scene);
            }
        }
        Err(SimError::Options(format!(
            "no scene of {} emitters lets each of {} orientations see {} of them: add emitters \
             or use fewer orientations",
            o.emitters, o.orientations, MIN_SEEN
        )))
    }

    fn try_draw(o: &InSituOptions, rng: &mut ChaCha8Rng) -> Option<Self> {
        let [w, d, h] = o.room_mm;
        let wall = rng.random_range(0..4);
        let along = rng.random_range(0.0..1.0);
        let off = rng.random_range(0.05..0.3) * 1000.0;
        let (x, y) = match wall {
            0 => (off, along * d),
            1 => (w - off, along * d),
            2 => (along * w, off),
            _ => (along * w, d - off),
        };
        let mount = Vector3::new(x, y, rng.random_range(1500.0..2400.0));
        let central = |rng: &mut ChaCha8Rng| {
            Vector3::new(
                rng.random_range(0.2 * w..0.8 * w),
                rng.random_range(0.2 * d..0.8 * d),
                rng.random_range(0.2 * h..0.8 * h),
            )
        };
        let first_aim = central(rng);
        let half_fov = (0.5 * o.geometry.lx.min(o.geometry.ly) / o.truth.intrinsics.f).atan();
        let mut poses = Vec::with_capacity(o.orientations);
        for k in 0..o.orientations {
            let axis = first_aim - mount;
            let aim = if k == 0 {
                first_aim
            } else {
                let perp = axis
                    .cross(&Vector3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    ))
                    .try_normalize(1e-9)?;
                let angle = rng.random_range(0.3..1.0) * o.pan_fraction * half_fov;
                let rot = nalgebra::Rotation3::from_axis_angle(&Unit::new_normalize(perp), angle);
                mount + rot * axis
            };
            let roll = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
            poses.push(look_at(&mount, &aim, roll)?);
        }
        let mut emitters = Vec::with_capacity(o.emitters);
        let truth = Model::standard(&o.truth);
        let mut tries = 0;
        while emitters.len() < o.emitters {
            tries += 1;
            if tries > 2000 * o.emitters {
                return None;
            }
            let e = Vector3::new(
                rng.random_range(0.0..w),
                rng.random_range(0.0..d),
                rng.random_range(0.0..h),
            );
            let pose = &poses[emitters.len() % o.orientations];
            if (e - mount).norm() >= 500.0
                && true_impact(&truth, &o.geometry, pose, &e, o.margin).is_some()
            {
                emitters.push(e);
            }
        }
        let sigma_m = point_sigma_mm(o.snr_db);
        let mut observations = Vec::with_capacity(o.orientations);
        for pose in &poses {
            let seen: Vec<(usize, Vector2<f64>)> = emitters
                .iter()
                .enumerate()
                .filter_map(|(j, e)| {
                    true_impact(&truth, &o.geometry, pose, e, o.margin).map(|m| (j, m))
                })
                .collect();
            if seen.len() < MIN_SEEN {
                return None;
            }
            observations.push(seen);
        }
        for image in &mut observations {
            for (_, m) in image.iter_mut() {
                let ex: f64 = rng.sample(StandardNormal);
                let ey: f64 = rng.sample(StandardNormal);
                *m += sigma_m * Vector2::new(ex, ey);
            }
        }
        let surveyed = emitters
            .iter()
            .map(|e| {
                let n: [f64; 3] = std::array::from_fn(|_| rng.sample(StandardNormal));
                e + o.survey_sigma_mm * Vector3::from(n)
            })
            .collect();
        Some(Self {
            options: o.clone(),
            emitters,
            surveyed,
            room_from_sensor: poses,
            observations,
            point_sigma_mm: sigma_m,
        })
    }

    /// Per orientation, the true `sensor_from_room` (what a calibration
    /// estimates as each image's pose).
    pub fn sensor_from_room(&self) -> Vec<Pose> {
        self.room_from_sensor.iter().map(Pose::inverse).collect()
    }
}
