//! A room of sensors calibrated by waving a wand (docs/network.md): the
//! rehearsal and test of a network calibration.
//!
//! World frame: the room's, `z` up, the floor at `z = 0`, the room
//! `[0, X] × [0, Y] × [0, Z]` mm. Eight sensor places (corners under the
//! ceiling aimed across the room, mid-walls aimed at each other, two low on
//! the short walls facing each other), each jittered (±150 mm in place,
//! ±300 mm in aim, a random roll); sensor `k > 8` reuses place `k mod 8`
//! one metre lower. A sensor's frame: `z` along its aim, `x ⟂ z`
//! horizontal-ish (rolled), `y = z × x`.
//!
//! Each sensor's true lens is the paper's lens 2 with its own small
//! differences (f ×(1 + 0.01 N), cx, cy + 0.05 N mm, k1 ×(1 + 0.05 N)); its
//! lab calibration is the truth plus a draw from the lab covariance
//! (diagonal: σ_f = 0.4 % f, σ_cx = σ_cy = 0.02 mm, σ_k1 = 3 % k1,
//! σ_k2 = 10 % k2), so that the prior is honest.
//!
//! The wand's centre follows two incommensurate sines per axis through the
//! central part of the room, its attitude three slow angles (yaw over a
//! full turn, pitch and roll ±60°), sampled at the frame rate. A sensor sees
//! an LED in front of it whose true impact lies on 95 % of its active area;
//! the measured point comes from the four electrode currents with Gaussian
//! amplitude noise of the chain's σ at the SNR (`SignalChain::amplitude_std`,
//! docs/model.md §6) and the balanced formula (§1). A fraction of frames is
//! corrupted: one sighting is replaced by a point anywhere on the area (a
//! reflection or a wrong LED). The static frame's LEDs lie on the floor,
//! measured by every sensor that sees them every [`STATIC_EVERY`] frames. Test emitters are drawn in
//! the same volume as the wand and kept when seen by two sensors or more.
//!
//! Draw order (ChaCha8 from the caller): sensors (place, aim, roll, lens,
//! lab error), the wand path's phases, then per frame the sightings' noise,
//! the bad frames, the static frame's sightings, the emitters.

use nalgebra::{DMatrix, Matrix3, Vector2, Vector3};
use psdcal_model::{
    psd::{electrode_currents, impact_point},
    Model, Param, Pose, PsdGeometry, SensorModel,
};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::room::true_impact;
use crate::signal::SignalChain;
use crate::SimError;

/// The static frame is measured once every this many frames.
pub const STATIC_EVERY: usize = 25;

/// A true and a measured impact point, when the LED is seen.
type Sighted = Result<Option<(Vector2<f64>, Vector2<f64>)>, SimError>;

/// What to simulate.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkRoomOptions {
    /// Room size, mm.
    pub room_mm: [f64; 3],
    /// Number of sensors (2 or more).
    pub sensors: usize,
    /// Waving time, s.
    pub duration_s: f64,
    /// Frame rate, Hz.
    pub rate_hz: f64,
    /// Per-channel SNR, dB (`None`: no noise).
    pub snr_db: Option<f64>,
    /// Fraction of frames with one wrong sighting.
    pub bad_fraction: f64,
    /// Whether the wand's three LEDs lie on one line.
    pub collinear_wand: bool,
    /// Test emitters.
    pub emitters: usize,
}

impl Default for NetworkRoomOptions {
    /// 6 × 5 × 3 m, 8 sensors, 60 s at 50 Hz, 40 dB, 3 % bad frames, a
    /// T-shaped wand, 50 test emitters.
    fn default() -> Self {
        Self {
            room_mm: [6000.0, 5000.0, 3000.0],
            sensors: 8,
            duration_s: 60.0,
            rate_hz: 50.0,
            snr_db: Some(40.0),
            bad_fraction: 0.03,
            collinear_wand: false,
            emitters: 50,
        }
    }
}

/// One simulated sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkRoomSensor {
    /// Its true pose.
    pub world_from_sensor: Pose,
    /// Its true lens.
    pub truth: SensorModel,
    /// Its lab calibration (truth plus a draw from `lab_covariance`).
    pub lab: SensorModel,
    /// The lab-estimated parameters.
    pub lab_params: Vec<Param>,
    /// Their lab covariance.
    pub lab_covariance: DMatrix<f64>,
}

/// Which LED a sighting is of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RoomLed {
    /// Wand LED `k`.
    Wand(usize),
    /// Static-frame LED `k`.
    Frame(usize),
}

/// One sighting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoomSighting {
    /// Frame index (0 for the static frame's).
    pub frame: usize,
    /// Sensor index.
    pub sensor: usize,
    /// The LED.
    pub led: RoomLed,
    /// Measured impact point, mm.
    pub measured: Vector2<f64>,
}

/// A simulated room.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkRoom {
    /// The sensors.
    pub sensors: Vec<NetworkRoomSensor>,
    /// The PSD's active area (every sensor).
    pub geometry: PsdGeometry,
    /// The wand's LEDs in its frame, mm.
    pub wand: Vec<Vector3<f64>>,
    /// The static frame's LEDs in the world, mm.
    pub frame_leds: Vec<Vector3<f64>>,
    /// The wand's true `world_from_wand` per frame.
    pub wand_poses: Vec<Pose>,
    /// Every sighting (wand, then the static frame's).
    pub sightings: Vec<RoomSighting>,
    /// Frames with a wrong sighting.
    pub bad_frames: Vec<usize>,
    /// Test emitters' true positions.
    pub emitters: Vec<Vector3<f64>>,
    /// Their sightings: (emitter, sensor, measured).
    pub emitter_sightings: Vec<(usize, usize, Vector2<f64>)>,
    /// RMS of measured − true impact over the clean sightings, mm per axis.
    pub point_sigma_mm: f64,
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// A pose at `at` looking at `target`, rolled by `roll` (module
/// documentation).
pub fn looking_at(at: Vector3<f64>, target: Vector3<f64>, roll: f64) -> Pose {
    let z = (target - at).normalize();
    let up = Vector3::z();
    let x0 = up.cross(&z);
    let x0 = if x0.norm() < 1e-9 {
        Vector3::x()
    } else {
        x0.normalize()
    };
    let y0 = z.cross(&x0);
    let (s, c) = roll.sin_cos();
    let x = x0 * c + y0 * s;
    let y = z.cross(&x);
    Pose::from_rotation(&Matrix3::from_columns(&[x, y, z]), at)
}

/// The eight places: (position, aim) as fractions of the room.
const PLACES: [([f64; 3], [f64; 3]); 8] = [
    ([0.03, 0.04, 0.93], [0.40, 0.40, 0.30]),
    ([0.97, 0.04, 0.93], [0.60, 0.40, 0.30]),
    ([0.97, 0.96, 0.93], [0.60, 0.60, 0.30]),
    ([0.03, 0.96, 0.93], [0.40, 0.60, 0.30]),
    ([0.50, 0.02, 0.96], [0.50, 0.62, 0.25]),
    ([0.50, 0.98, 0.96], [0.50, 0.38, 0.25]),
    ([0.02, 0.50, 0.50], [0.62, 0.50, 0.40]),
    ([0.98, 0.50, 0.50], [0.38, 0.50, 0.40]),
];

fn draw_sensor(k: usize, room: &[f64; 3], rng: &mut ChaCha8Rng) -> NetworkRoomSensor {
    let (place, aim) = PLACES[k % PLACES.len()];
    let lower = (k / PLACES.len()) as f64 * 1000.0;
    let mut at = Vector3::from_fn(|i, _| place[i] * room[i]);
    at.z = (at.z - lower).max(300.0);
    let target = Vector3::from_fn(|i, _| aim[i] * room[i]);
    let at = at + Vector3::from_fn(|_, _| 150.0 * (2.0 * rng.random::<f64>() - 1.0));
    let target = target + Vector3::from_fn(|_, _| 300.0 * (2.0 * rng.random::<f64>() - 1.0));
    let roll = std::f64::consts::PI * (2.0 * rng.random::<f64>() - 1.0);
    let world_from_sensor = looking_at(at, target, roll);
    let mut truth = SensorModel::paper_lens2();
    truth.intrinsics.f *= 1.0 + 0.01 * normal(rng);
    truth.intrinsics.cx += 0.05 * normal(rng);
    truth.intrinsics.cy += 0.05 * normal(rng);
    truth.distortion.k1 *= 1.0 + 0.05 * normal(rng);
    let lab_params = vec![Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2];
    let sigmas = [
        0.004 * truth.intrinsics.f,
        0.02,
        0.02,
        0.03 * truth.distortion.k1.abs(),
        0.1 * truth.distortion.k2.abs().max(1e-6),
    ];
    let lab_covariance = DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(
        5,
        sigmas.iter().map(|s| s * s),
    ));
    let mut lab = truth;
    for (p, s) in lab_params.iter().zip(sigmas) {
        lab.set(*p, truth.get(*p) + s * normal(rng));
    }
    NetworkRoomSensor {
        world_from_sensor,
        truth,
        lab,
        lab_params,
        lab_covariance,
    }
}

/// The measured point of a true impact point through the electrode noise.
fn measure(
    chain: &SignalChain,
    geometry: &PsdGeometry,
    point: &Vector2<f64>,
    snr_db: Option<f64>,
    rng: &mut ChaCha8Rng,
) -> Result<Vector2<f64>, SimError> {
    let clean = electrode_currents(geometry, point, 1.0);
    let Some(snr) = snr_db else {
        return Ok(*point);
    };
    let mut noisy = clean;
    for v in [
        &mut noisy.vx1,
        &mut noisy.vx2,
        &mut noisy.vy1,
        &mut noisy.vy2,
    ] {
        let sigma = chain
            .amplitude_std(*v, snr)
            .map_err(|e| SimError::Options(format!("noise at {snr} dB: {e}")))?;
        *v += sigma * normal(rng);
    }
    impact_point(geometry, &noisy).map_err(|e| SimError::Options(e.to_string()))
}

/// The wand's pose at time `t` (module documentation).
fn wand_pose(room: &[f64; 3], phases: &[f64; 12], t: f64) -> Pose {
    let periods = [23.0, 9.7, 17.0, 7.3, 13.0, 5.9];
    let centre = Vector3::from_fn(|i, _| {
        let (lo, hi) = ([0.22, 0.22, 0.15][i], [0.78, 0.78, 0.75][i]);
        let mid = 0.5 * (lo + hi) * room[i];
        let half = 0.5 * (hi - lo) * room[i];
        let w1 = std::f64::consts::TAU / periods[2 * i];
        let w2 = std::f64::consts::TAU / periods[2 * i + 1];
        mid + half
            * (0.65 * (w1 * t + phases[2 * i]).sin() + 0.35 * (w2 * t + phases[2 * i + 1]).sin())
    });
    let yaw = std::f64::consts::TAU * t / 11.0 + phases[6];
    let pitch = 1.0 * (std::f64::consts::TAU * t / 6.1 + phases[7]).sin();
    let roll = 1.0 * (std::f64::consts::TAU * t / 4.3 + phases[8]).sin();
    let r = Pose::new(Vector3::z() * yaw, Vector3::zeros()).rotation()
        * Pose::new(Vector3::y() * pitch, Vector3::zeros()).rotation()
        * Pose::new(Vector3::x() * roll, Vector3::zeros()).rotation();
    Pose::from_rotation(&r, centre)
}

impl NetworkRoom {
    /// Simulates a room (module documentation).
    pub fn simulate(
        options: &NetworkRoomOptions,
        chain: &SignalChain,
        rng: &mut ChaCha8Rng,
    ) -> Result<Self, SimError> {
        let o = options;
        let frames = (o.duration_s * o.rate_hz).round();
        let valid = o.sensors >= 2
            && (1.0..=1e7).contains(&frames)
            && o.room_mm.iter().all(|v| v.is_finite() && *v >= 1000.0)
            && (0.0..=0.5).contains(&o.bad_fraction);
        if !valid {
            return Err(SimError::Options(format!(
                "a network room needs at least 2 sensors ({}), 1 to 10⁷ frames ({frames}), room \
                 sides of at least 1000 mm ({:?}) and a bad fraction in [0, 0.5] ({})",
                o.sensors, o.room_mm, o.bad_fraction
            )));
        }
        let frames = frames as usize;
        let geometry = PsdGeometry::default();
        let sensors: Vec<_> = (0..o.sensors)
            .map(|k| draw_sensor(k, &o.room_mm, rng))
            .collect();
        let truths: Vec<Model> = sensors.iter().map(|s| Model::standard(&s.truth)).collect();
        let wand = if o.collinear_wand {
            vec![
                Vector3::zeros(),
                Vector3::new(200.0, 0.0, 0.0),
                Vector3::new(500.0, 0.0, 0.0),
            ]
        } else {
            vec![
                Vector3::zeros(),
                Vector3::new(500.0, 0.0, 0.0),
                Vector3::new(200.0, 150.0, 0.0),
            ]
        };
        let [rx, ry, _] = o.room_mm;
        let frame_leds = vec![
            Vector3::new(0.4 * rx, 0.4 * ry, 0.0),
            Vector3::new(0.4 * rx + 800.0, 0.4 * ry, 0.0),
            Vector3::new(0.4 * rx + 1200.0, 0.4 * ry, 0.0),
            Vector3::new(0.4 * rx, 0.4 * ry + 600.0, 0.0),
        ];
        let phases: [f64; 12] =
            std::array::from_fn(|_| std::f64::consts::TAU * rng.random::<f64>());
        let mut sightings = Vec::new();
        let mut wand_poses = Vec::with_capacity(frames);
        let (mut ss, mut n) = (0.0, 0usize);
        let see = |s: usize, p: &Vector3<f64>, rng: &mut ChaCha8Rng| -> Sighted {
            let Some(m) = true_impact(
                &truths[s],
                &geometry,
                &sensors[s].world_from_sensor,
                p,
                0.95,
            ) else {
                return Ok(None);
            };
            let measured = measure(chain, &geometry, &m, o.snr_db, rng)?;
            Ok(Some((m, measured)))
        };
        let mut starts = Vec::with_capacity(frames + 1);
        for f in 0..frames {
            starts.push(sightings.len());
            let pose = wand_pose(&o.room_mm, &phases, f as f64 / o.rate_hz);
            for (l, led) in wand.iter().enumerate() {
                let p = pose.transform(led);
                for s in 0..o.sensors {
                    if let Some((m, measured)) = see(s, &p, rng)? {
                        ss += (measured - m).norm_squared();
                        n += 1;
                        sightings.push(RoomSighting {
                            frame: f,
                            sensor: s,
                            led: RoomLed::Wand(l),
                            measured,
                        });
                    }
                }
            }
            wand_poses.push(pose);
        }
        starts.push(sightings.len());
        let mut bad_frames = Vec::new();
        for f in 0..frames {
            if rng.random::<f64>() < o.bad_fraction {
                let (a, b) = (starts[f], starts[f + 1]);
                if a == b {
                    continue;
                }
                let k = rng.random_range(a..b);
                sightings[k].measured = Vector2::new(
                    0.4 * geometry.lx * (2.0 * rng.random::<f64>() - 1.0),
                    0.4 * geometry.ly * (2.0 * rng.random::<f64>() - 1.0),
                );
                bad_frames.push(f);
            }
        }
        for f in (0..frames).step_by(STATIC_EVERY) {
            for (l, p) in frame_leds.iter().enumerate() {
                for s in 0..o.sensors {
                    if let Some((_, measured)) = see(s, p, rng)? {
                        sightings.push(RoomSighting {
                            frame: f,
                            sensor: s,
                            led: RoomLed::Frame(l),
                            measured,
                        });
                    }
                }
            }
        }
        let mut emitters = Vec::new();
        let mut emitter_sightings = Vec::new();
        let mut tries = 0;
        while emitters.len() < o.emitters && tries < 1000 * o.emitters.max(1) {
            tries += 1;
            let t = rng.random::<f64>() * o.duration_s;
            let mut p = wand_pose(&o.room_mm, &phases, t).t;
            p += Vector3::from_fn(|_, _| 200.0 * normal(rng));
            let seen: Vec<usize> = (0..o.sensors)
                .filter(|&s| {
                    true_impact(
                        &truths[s],
                        &geometry,
                        &sensors[s].world_from_sensor,
                        &p,
                        0.95,
                    )
                    .is_some()
                })
                .collect();
            if seen.len() < 2 {
                continue;
            }
            for s in seen {
                if let Some((_, measured)) = see(s, &p, rng)? {
                    emitter_sightings.push((emitters.len(), s, measured));
                }
            }
            emitters.push(p);
        }
        Ok(Self {
            sensors,
            geometry,
            wand,
            frame_leds,
            wand_poses,
            sightings,
            bad_frames,
            emitters,
            emitter_sightings,
            point_sigma_mm: (ss / (2 * n.max(1)) as f64).sqrt(),
        })
    }
}
