//! A room for positioning: sensors on the ceiling looking down at emitters
//! on the floor (docs/model.md §5.3), and each emitter observed through a
//! sensor's true model and signal chain.
//!
//! World frame: `z` up, the floor at `z = 0`. The sensors hang at height
//! `H` on a circle of diameter `B` (the baseline; two sensors sit at
//! `x = ±B/2`, `y = 0`), each looking straight down: `world_from_sensor`
//! is the rotation by π about `x` (sensor `x` = world `x`, sensor `y` =
//! world `−y`, the optical axis = world `−z`) and the translation
//! `(x_k, y_k, H)`. Emitters are drawn uniformly on the floor square that
//! holds the sensors' views and kept when every sensor images them inside
//! the central `margin` fraction of its active area (rejection sampling).
//!
//! An observation: the emitter in the sensor frame `P_s = R⁻¹ (P_w − t)`,
//! its ideal point by the pinhole (docs/model.md §3), the true impact point
//! by the true distortion (§2), then the electrode currents, the chain's
//! noise at the SNR, band-pass and demodulation, and the balanced formula
//! (`SignalChain::measure_point`, §1, §6).

use nalgebra::{Vector2, Vector3};
use psdcal_model::{ChannelGains, Model, Pose, PsdGeometry, SensorModel};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::signal::SignalChain;
use crate::SimError;

/// The layout of a room.
#[derive(Debug, Clone, PartialEq)]
pub struct RoomOptions {
    /// Number of sensors (at least 2).
    pub sensors: usize,
    /// Height of the sensors above the floor, mm.
    pub height_mm: f64,
    /// Baseline: the diameter of the circle of sensors, mm.
    pub baseline_mm: f64,
    /// Number of emitters (at least 1).
    pub emitters: usize,
    /// Fraction of the active area (about its centre) an emitter's image
    /// must fall in on every sensor, in (0, 1].
    pub margin: f64,
}

impl Default for RoomOptions {
    /// Two sensors 1 m apart, 2.5 m above 100 emitters, images within the
    /// central 80 % of the active area.
    fn default() -> Self {
        Self {
            sensors: 2,
            height_mm: 2500.0,
            baseline_mm: 1000.0,
            emitters: 100,
            margin: 0.8,
        }
    }
}

/// A room: the sensors' poses and the emitters' true positions.
#[derive(Debug, Clone, PartialEq)]
pub struct Room {
    /// Each sensor's `world_from_sensor`.
    pub sensors: Vec<Pose>,
    /// Each emitter's true position, mm.
    pub emitters: Vec<Vector3<f64>>,
}

/// The true impact point of `emitter` on a sensor (`truth`, posed at
/// `world_from_sensor`), or `None` when it is behind the sensor or off the
/// central `margin` of the active area.
pub fn true_impact(
    truth: &Model,
    geometry: &PsdGeometry,
    world_from_sensor: &Pose,
    emitter: &Vector3<f64>,
    margin: f64,
) -> Option<Vector2<f64>> {
    let p = world_from_sensor.inverse().transform(emitter);
    let ideal = truth.ideal_of_point(&p).ok()?;
    let m = truth.measured_from_ideal_to_tolerance(&ideal).ok()?;
    (m.x.abs() <= 0.5 * margin * geometry.lx && m.y.abs() <= 0.5 * margin * geometry.ly)
        .then_some(m)
}

impl Room {
    /// Lays out the sensors and draws the emitters (module documentation).
    pub fn draw(
        options: &RoomOptions,
        truth: &SensorModel,
        geometry: &PsdGeometry,
        rng: &mut ChaCha8Rng,
    ) -> Result<Self, SimError> {
        let o = options;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if o.sensors < 2
            || o.emitters == 0
            || !positive(o.height_mm)
            || !positive(o.margin)
            || o.margin > 1.0
            || !(o.baseline_mm.is_finite() && o.baseline_mm >= 0.0)
        {
            return Err(SimError::Options(format!(
                "a room needs at least 2 sensors ({}), 1 emitter ({}), a positive height ({} \
                 mm), a baseline ≥ 0 ({} mm) and a margin in (0, 1] ({})",
                o.sensors, o.emitters, o.height_mm, o.baseline_mm, o.margin
            )));
        }
        let down = Vector3::new(std::f64::consts::PI, 0.0, 0.0);
        let sensors: Vec<Pose> = (0..o.sensors)
            .map(|k| {
                let phi = std::f64::consts::TAU * k as f64 / o.sensors as f64;
                let r = 0.5 * o.baseline_mm;
                Pose::new(
                    down,
                    Vector3::new(r * phi.cos(), r * phi.sin(), o.height_mm),
                )
            })
            .collect();
        // Half the floor width one sensor sees, plus the circle's radius.
        let half = o.height_mm * 0.5 * geometry.lx.max(geometry.ly) / truth.intrinsics.f
            + 0.5 * o.baseline_mm;
        let mut emitters = Vec::with_capacity(o.emitters);
        let mut tries = 0usize;
        let chain = Model::standard(truth);
        while emitters.len() < o.emitters {
            tries += 1;
            if tries > 1000 * o.emitters {
                return Err(SimError::Options(format!(
                    "no floor point is seen by all {} sensors within {} % of their active area: \
                     shorten the baseline ({} mm) or raise the sensors ({} mm)",
                    o.sensors,
                    100.0 * o.margin,
                    o.baseline_mm,
                    o.height_mm
                )));
            }
            let e = Vector3::new(
                rng.random_range(-half..half),
                rng.random_range(-half..half),
                0.0,
            );
            if sensors
                .iter()
                .all(|s| true_impact(&chain, geometry, s, &e, o.margin).is_some())
            {
                emitters.push(e);
            }
        }
        Ok(Self { sensors, emitters })
    }
}

/// What one sensor measured of one emitter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmitterObservation {
    /// The true impact point, mm.
    pub true_measured: Vector2<f64>,
    /// The impact point from the demodulated amplitudes, mm.
    pub measured: Vector2<f64>,
}

/// A sensor as the room's emitters reach it: its true model and active
/// area, its signal chain, the spot's photocurrent and the channels' SNR.
#[derive(Debug, Clone, Copy)]
pub struct RoomSensor<'a> {
    /// The sensor's true model (the standard chain of its parameters,
    /// `Model::standard`).
    pub truth: &'a Model,
    /// Its active area.
    pub geometry: &'a PsdGeometry,
    /// Its electrode signal chain.
    pub chain: &'a SignalChain,
    /// Photocurrent of an emitter's spot, A.
    pub i0: f64,
    /// Per-channel SNR, dB (no noise when `None`).
    pub snr_db: Option<f64>,
}

/// Observes `emitter` with `sensor` posed at `world_from_sensor`, through
/// its chain with balanced gains (module documentation).
pub fn observe_emitter(
    sensor: &RoomSensor<'_>,
    world_from_sensor: &Pose,
    emitter: &Vector3<f64>,
    rng: &mut ChaCha8Rng,
) -> Result<EmitterObservation, SimError> {
    let RoomSensor {
        truth,
        geometry,
        chain,
        i0,
        snr_db,
    } = *sensor;
    let true_measured =
        true_impact(truth, geometry, world_from_sensor, emitter, 1.0).ok_or_else(|| {
            SimError::Options(format!(
                "emitter {:?} mm is not imaged on the sensor's active area",
                emitter.as_slice()
            ))
        })?;
    let (_, measured) = chain.measure_point(
        geometry,
        &true_measured,
        i0,
        &ChannelGains::UNIT,
        snr_db,
        rng,
    )?;
    Ok(EmitterObservation {
        true_measured,
        measured,
    })
}
