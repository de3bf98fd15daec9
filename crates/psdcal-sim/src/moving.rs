//! Moving LEDs seen by a rig (docs/model.md §9): the recording a card
//! sampling every sensor's four channels would make while LEDs, each
//! modulated at its own tone, move through the room.
//!
//! # Scene ([`MovingScene::ceiling_corners`])
//!
//! Four sensors at the corners of a 5 m × 4 m ceiling, 2.8 m above the
//! floor, each looking at the point `(0, 0, 1000)` mm (world frame: `z` up,
//! origin on the floor at the room's centre). Two LEDs 2–5 m from the
//! sensors:
//!
//! - `a` (1 000 Hz): a circle of radius 700 mm about `(0, 0, 1000)` at
//!   0.85 m/s (centripetal acceleration ≈ 1 m/s²);
//! - `b` (1 300 Hz): back and forth along `x` between −700 and 700 mm at
//!   `y = 300`, `z = 800`, each crossing a cosine ramp of 2.2 s (peak speed
//!   1.0 m/s), then a pause of 1.5 s.
//!
//! # Signal
//!
//! Channel `k` of sensor `s` at sample `n` (`t = n / fs`):
//!
//! ```text
//! x_sk[n] = Σ_i V_sik(t) sin(2π f_i (1 + ε) t + φ_i) + e_sk[n] + dc_k + hum + drift, quantised
//! ```
//!
//! `V_si(t)`: the electrode amplitudes of LED `i`'s true impact point on
//! sensor `s` (the true model; zero when off the central 95 % of the active
//! area or behind the sensor) for a photocurrent `A₀ (1 m / d)²`, `d` the
//! distance; computed every [`KNOT_SAMPLES`] samples and interpolated
//! linearly between. `φ_i` uniform, once; `e_sk` white, σ = `noise_v`;
//! the impairments those of [`crate::raw`] (DC, hum, drift, quantisation,
//! clock; no switching transient: the LEDs never switch).
//!
//! # Random numbers
//!
//! From the caller's ChaCha8: the hum phase, one phase per LED, then per
//! sample the `4 S` channels' standard normals.

use std::f64::consts::{PI, TAU};

use nalgebra::{Vector2, Vector3};
use psdcal_model::psd::electrode_currents;
use psdcal_model::{Model, Pose, PsdGeometry};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use crate::raw::{Impairments, FULL_SCALE_V, QUANTUM_V};
use crate::room::true_impact;
use crate::SimError;

/// Samples between two computations of the amplitudes.
pub const KNOT_SAMPLES: usize = 20;

/// One LED: its name, tone and path.
#[derive(Debug, Clone, PartialEq)]
pub struct MovingLed {
    /// Its name (tones.csv's `led`).
    pub name: String,
    /// Its modulation, Hz.
    pub frequency_hz: f64,
    /// Its path.
    pub path: LedPath,
}

/// Where an LED is when.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LedPath {
    /// A horizontal circle: centre (mm), radius (mm), speed (mm/s).
    Circle {
        /// Centre, mm.
        centre: [f64; 3],
        /// Radius, mm.
        radius_mm: f64,
        /// Speed, mm/s.
        speed_mm_s: f64,
    },
    /// Back and forth along `x` from `from` to `from + (length, 0, 0)`:
    /// cosine ramps of `ramp_s`, pauses of `pause_s` at each end.
    Shuttle {
        /// Start, mm.
        from: [f64; 3],
        /// Length along x, mm.
        length_mm: f64,
        /// Duration of one crossing, s.
        ramp_s: f64,
        /// Pause at each end, s.
        pause_s: f64,
    },
}

impl LedPath {
    /// The position at `t` (s), mm.
    pub fn position(&self, t: f64) -> Vector3<f64> {
        match *self {
            LedPath::Circle {
                centre,
                radius_mm,
                speed_mm_s,
            } => {
                let phi = speed_mm_s / radius_mm * t;
                Vector3::new(
                    centre[0] + radius_mm * phi.cos(),
                    centre[1] + radius_mm * phi.sin(),
                    centre[2],
                )
            }
            LedPath::Shuttle {
                from,
                length_mm,
                ramp_s,
                pause_s,
            } => {
                let period = 2.0 * (ramp_s + pause_s);
                let tau = t.rem_euclid(period);
                let s = |u: f64| 0.5 * (1.0 - (PI * u.clamp(0.0, 1.0)).cos());
                let fraction = if tau < ramp_s {
                    s(tau / ramp_s)
                } else if tau < ramp_s + pause_s {
                    1.0
                } else if tau < 2.0 * ramp_s + pause_s {
                    1.0 - s((tau - ramp_s - pause_s) / ramp_s)
                } else {
                    0.0
                };
                Vector3::new(from[0] + length_mm * fraction, from[1], from[2])
            }
        }
    }
}

/// The rig and the LEDs.
#[derive(Debug, Clone, PartialEq)]
pub struct MovingScene {
    /// Each sensor's `world_from_sensor`.
    pub sensors: Vec<Pose>,
    /// The LEDs.
    pub leds: Vec<MovingLed>,
}

/// `world_from_sensor` of a sensor at `at` looking at `target` (the
/// sensor's `z` towards it, its `y` as close to the world's `−z` as
/// possible).
pub fn looking_at(at: Vector3<f64>, target: Vector3<f64>) -> Pose {
    let z = (target - at).normalize();
    let down = Vector3::new(0.0, 0.0, -1.0);
    let x = down.cross(&z).normalize();
    let y = z.cross(&x);
    let r = nalgebra::Matrix3::from_columns(&[x, y, z]);
    let rotation = nalgebra::Rotation3::from_matrix_unchecked(r);
    let rvec = rotation.scaled_axis();
    Pose::new(rvec, at)
}

impl MovingScene {
    /// The scene of the module documentation.
    pub fn ceiling_corners() -> Self {
        let target = Vector3::new(0.0, 0.0, 1000.0);
        let sensors = [
            (-2500.0, -2000.0),
            (2500.0, -2000.0),
            (2500.0, 2000.0),
            (-2500.0, 2000.0),
        ]
        .iter()
        .map(|&(x, y)| looking_at(Vector3::new(x, y, 2800.0), target))
        .collect();
        let leds = vec![
            MovingLed {
                name: "a".to_string(),
                frequency_hz: 1000.0,
                path: LedPath::Circle {
                    centre: [0.0, 0.0, 1000.0],
                    radius_mm: 700.0,
                    speed_mm_s: 850.0,
                },
            },
            MovingLed {
                name: "b".to_string(),
                frequency_hz: 1300.0,
                path: LedPath::Shuttle {
                    from: [-700.0, 300.0, 800.0],
                    length_mm: 1400.0,
                    ramp_s: 2.2,
                    pause_s: 1.5,
                },
            },
        ];
        Self { sensors, leds }
    }
}

/// The recording to synthesise.
#[derive(Debug, Clone, PartialEq)]
pub struct MovingPlan {
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Samples.
    pub samples: usize,
    /// Photocurrent at 1 m, V (the sum of the four channels' amplitudes).
    pub amplitude_at_1m_v: f64,
    /// White noise per channel, V.
    pub noise_v: f64,
    /// The card's impairments (the transient is not used).
    pub impairments: Impairments,
}

impl MovingPlan {
    /// Synthesises the recording of `scene` through the sensors' true
    /// model `truth` and hands it to `sink` in blocks of rows (`4 S` values
    /// each, the sensors in the scene's order).
    ///
    /// Errors: a non-positive rate, amplitude or negative noise; a tone at
    /// or above fs/2; the sink's error.
    pub fn generate<E: From<SimError>>(
        &self,
        scene: &MovingScene,
        truth: &Model,
        geometry: &PsdGeometry,
        rng: &mut ChaCha8Rng,
        mut sink: impl FnMut(&[f64]) -> Result<(), E>,
    ) -> Result<(), E> {
        let fs = self.sample_rate_hz;
        let bad = |m: String| E::from(SimError::Options(m));
        if !(fs.is_finite() && fs > 0.0 && self.amplitude_at_1m_v > 0.0) {
            return Err(bad(format!(
                "rate {fs} Hz, amplitude {} V",
                self.amplitude_at_1m_v
            )));
        }
        if !(self.noise_v.is_finite() && self.noise_v >= 0.0) {
            return Err(bad(format!(
                "noise {} V: must be finite and ≥ 0",
                self.noise_v
            )));
        }
        if let Some(led) = scene
            .leds
            .iter()
            .find(|l| !(l.frequency_hz > 0.0 && l.frequency_hz < fs / 2.0))
        {
            return Err(bad(format!(
                "a tone of {} Hz: must lie between 0 and fs/2",
                led.frequency_hz
            )));
        }
        let imp = &self.impairments;
        let clock = 1.0 + imp.clock_ppm * 1e-6;
        let hum_phase = TAU * rng.random::<f64>();
        let phases: Vec<f64> = scene
            .leds
            .iter()
            .map(|_| TAU * rng.random::<f64>())
            .collect();
        let width = 4 * scene.sensors.len();
        let amplitudes = |t: f64| -> Vec<[f64; 4]> {
            let mut out = Vec::with_capacity(scene.sensors.len() * scene.leds.len());
            for pose in &scene.sensors {
                for led in &scene.leds {
                    let p = led.path.position(t);
                    let d = (p - pose.t).norm();
                    let i0 = self.amplitude_at_1m_v * (1000.0 / d).powi(2);
                    out.push(match true_impact(truth, geometry, pose, &p, 0.95) {
                        Some(m) => {
                            let a = electrode_currents(geometry, &Vector2::new(m.x, m.y), i0);
                            [a.vx1, a.vx2, a.vy1, a.vy2]
                        }
                        None => [0.0; 4],
                    });
                }
            }
            out
        };
        let leds = scene.leds.len();
        let mut block = Vec::with_capacity(KNOT_SAMPLES * width);
        let mut next = amplitudes(0.0);
        let mut first = 0;
        while first < self.samples {
            let now = next;
            next = amplitudes((first + KNOT_SAMPLES) as f64 / fs);
            block.clear();
            for n in first..(first + KNOT_SAMPLES).min(self.samples) {
                let t = n as f64 / fs;
                let w = (n - first) as f64 / KNOT_SAMPLES as f64;
                let mut common = 0.0;
                if imp.hum_v != 0.0 {
                    common += imp.hum_v
                        * ((TAU * 50.0 * t + hum_phase).sin()
                            + (TAU * 150.0 * t).sin() / 3.0
                            + (TAU * 250.0 * t).sin() / 5.0);
                }
                if imp.drift_v_per_s != 0.0 {
                    common += imp.drift_v_per_s * t + 0.05 * (TAU * 0.1 * t).sin();
                }
                let tones: Vec<f64> = scene
                    .leds
                    .iter()
                    .zip(&phases)
                    .map(|(led, phase)| {
                        let turns = (led.frequency_hz * clock * n as f64 / fs).fract();
                        (TAU * turns + phase).sin()
                    })
                    .collect();
                for s in 0..scene.sensors.len() {
                    for k in 0..4 {
                        let mut x = common + imp.dc_offset_v[k];
                        for (i, tone) in tones.iter().enumerate() {
                            let a = now[s * leds + i][k] * (1.0 - w) + next[s * leds + i][k] * w;
                            x += a * tone;
                        }
                        if self.noise_v > 0.0 {
                            let e: f64 = rng.sample(StandardNormal);
                            x += self.noise_v * e;
                        }
                        if imp.quantise {
                            x = ((x / QUANTUM_V).round() * QUANTUM_V)
                                .clamp(-FULL_SCALE_V, FULL_SCALE_V - QUANTUM_V);
                        }
                        block.push(x);
                    }
                }
            }
            sink(&block)?;
            first += KNOT_SAMPLES;
        }
        Ok(())
    }
}
