//! One simulated calibration data set: the paper's signal chain end to end
//! (docs/model.md §1, §6, §7).
//!
//! For every template pose and LED: the LED's ideal image point
//! (pinhole, docs/model.md §3) is distorted by the lens and — when switched on —
//! the PSD (`Model::measured_from_ideal_to_tolerance`, §2) into the true impact point; the
//! pin-cushion forward model gives the four electrode currents for a total
//! photocurrent `I0` (§1); the amplifiers multiply them by their gains (the
//! chain's amplifier gain (`ChainConfig::amplifier_gain_v_per_a`), times the relative gains when the
//! imbalance is switched on, (P43)); the signal chain modulates, adds noise at
//! the requested SNR, band-pass filters and demodulates each channel (§6,
//! [`crate::signal`]); and the impact point is computed from the demodulated
//! amplitudes with the balanced formula (the calibration does not know the
//! gains). With the PSD's non-linearity switched on, the currents are those
//! of the point the PSD reports for the true spot ([`crate::nonlinearity`]).
//! Without noise the chain is skipped: it returns the amplitudes
//! exactly (its own tests show it), and skipping keeps noise-free studies fast.

use nalgebra::Vector2;
use psdcal_model::psd::{electrode_currents, impact_point};
use psdcal_model::{Amplitudes, ChannelGains, Model, Pose, PsdGeometry, SensorModel};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::nonlinearity::PsdNonlinearity;
use crate::scenario::{draw_imbalance, draw_poses, Lens, Template, TemplateKind};
use crate::signal::SignalChain;
use crate::SimError;

/// Total photocurrent of one LED's spot, A (20 µA: about 1.9 V summed over
/// the four channels at the nominal gain at 1 kHz).
pub const DEFAULT_PHOTOCURRENT_A: f64 = 20e-6;

/// What to simulate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SimulationOptions {
    /// The lens.
    pub lens: Lens,
    /// Per-channel SNR, dB (`None`: no noise).
    pub snr_db: Option<f64>,
    /// Amplifier gain imbalance (P43).
    pub imbalance: bool,
    /// The PSD's own distortion, `l1 = −1.3058e-3`.
    pub psd_distortion: bool,
    /// The PSD's non-radial non-linearity ([`crate::PsdNonlinearity`]):
    /// the currents are those of the point the PSD reports.
    #[serde(default)]
    pub psd_nonlinearity: bool,
    /// Number of images (template poses).
    pub images: usize,
    /// The template.
    pub template: TemplateKind,
    /// The PSD's active area.
    pub geometry: PsdGeometry,
    /// LED spot photocurrent, A.
    pub photocurrent_a: f64,
    /// The signal chain.
    #[serde(skip)]
    pub chain: SignalChain,
}

impl Default for SimulationOptions {
    /// The paper's lens 2 at 40 dB with nine images of the 14-LED template.
    fn default() -> Self {
        Self {
            lens: Lens::Two,
            snr_db: Some(40.0),
            imbalance: false,
            psd_distortion: false,
            psd_nonlinearity: false,
            images: 9,
            template: TemplateKind::Scatter14,
            geometry: PsdGeometry::default(),
            photocurrent_a: DEFAULT_PHOTOCURRENT_A,
            chain: SignalChain::default(),
        }
    }
}

/// One simulated point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimulatedPoint {
    /// LED index in the template.
    pub led: usize,
    /// Ideal (pinhole) image point, mm.
    pub ideal: Vector2<f64>,
    /// True impact point (after lens and PSD distortion), mm.
    pub true_measured: Vector2<f64>,
    /// Demodulated electrode amplitudes, V.
    pub amplitudes: Amplitudes,
    /// Impact point computed from the amplitudes (balanced formula), mm.
    pub measured: Vector2<f64>,
}

/// One simulated image.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulatedImage {
    /// Image id (`1`, `2`, …).
    pub id: String,
    /// Its points.
    pub points: Vec<SimulatedPoint>,
}

/// A simulated data set with its truth.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulation {
    /// The options it was made with.
    pub options: SimulationOptions,
    /// The true sensor model (with `l1` when the PSD distorts).
    pub truth: SensorModel,
    /// The true relative channel gains (unit without imbalance).
    pub gains: ChannelGains,
    /// The absolute gain of channel x1, V/A.
    pub gain_x1: f64,
    /// The true `sensor_from_template` poses.
    pub poses: Vec<Pose>,
    /// The template.
    pub template: Template,
    /// The images.
    pub images: Vec<SimulatedImage>,
}

/// Simulates a data set (module documentation); every random draw comes from
/// `rng`: poses, then gains (drawn even without imbalance), then noise.
pub fn simulate(options: &SimulationOptions, rng: &mut ChaCha8Rng) -> Result<Simulation, SimError> {
    check_options(options)?;
    let truth = true_model(options);
    let template = options.template.template();
    let poses =
        draw_poses(&truth, &options.geometry, &template, options.images, rng).ok_or_else(|| {
            SimError::Options(
                "no template pose keeps every LED on the active area for this lens and sensor"
                    .into(),
            )
        })?;
    simulate_with(options, truth, template, poses, rng)
}

/// Simulates a data set at the given `sensor_from_template` poses (one
/// image each, `options.images` ignored) instead of drawn ones; every
/// random draw comes from `rng`: gains (drawn even without imbalance), then
/// noise. Refuses fewer than 3 poses and a pose that puts an LED off the
/// active area, naming the image (`1, 2, …`) and the LED (`#1, …`).
pub fn simulate_at(
    options: &SimulationOptions,
    poses: &[Pose],
    rng: &mut ChaCha8Rng,
) -> Result<Simulation, SimError> {
    let options = SimulationOptions {
        images: poses.len(),
        ..options.clone()
    };
    check_options(&options)?;
    let truth = true_model(&options);
    let template = options.template.template();
    let (hx, hy) = (0.5 * options.geometry.lx, 0.5 * options.geometry.ly);
    let chain = Model::standard(&truth);
    for (i, pose) in poses.iter().enumerate() {
        for (led, xy) in template.leds.iter().enumerate() {
            let inside = chain
                .project_to_tolerance(pose, xy)
                .is_ok_and(|m| m.x.abs() < hx && m.y.abs() < hy);
            if !inside {
                return Err(SimError::Options(format!(
                    "pose {} puts LED #{} of the template off the active area; move or turn that pose",
                    i + 1,
                    led + 1
                )));
            }
        }
    }
    simulate_with(&options, truth, template, poses.to_vec(), rng)
}

fn check_options(options: &SimulationOptions) -> Result<(), SimError> {
    if options.images < 3 {
        return Err(SimError::Options(format!(
            "{} image(s) requested; a calibration needs at least 3",
            options.images
        )));
    }
    if !(options.photocurrent_a.is_finite() && options.photocurrent_a > 0.0) {
        return Err(SimError::Options(
            "the photocurrent must be positive".into(),
        ));
    }
    Ok(())
}

fn true_model(options: &SimulationOptions) -> SensorModel {
    let mut truth = options.lens.model();
    if options.psd_distortion {
        truth.distortion.l1 = SensorModel::PAPER_L1;
    }
    truth
}

fn simulate_with(
    options: &SimulationOptions,
    truth: SensorModel,
    template: Template,
    poses: Vec<Pose>,
    rng: &mut ChaCha8Rng,
) -> Result<Simulation, SimError> {
    // The imbalance is drawn whether or not it is used, so that the noise
    // that follows is the same with and without it (common random numbers:
    // a seed's balanced and unbalanced data differ by the gains alone).
    let drawn = draw_imbalance(rng);
    let gains = if options.imbalance {
        drawn
    } else {
        ChannelGains::UNIT
    };
    let gain_x1 = options.chain.config().amplifier_gain_v_per_a;
    let model = Model::standard(&truth);
    let mut images = Vec::with_capacity(poses.len());
    for (i, pose) in poses.iter().enumerate() {
        let mut points = Vec::with_capacity(template.leds.len());
        for (led, xy) in template.leds.iter().enumerate() {
            let ideal = model.project_ideal(pose, xy)?;
            let true_measured = model.measured_from_ideal_to_tolerance(&ideal)?;
            let reported = if options.psd_nonlinearity {
                PsdNonlinearity::new(options.geometry).reported(&true_measured)
            } else {
                true_measured
            };
            let clean = scale(
                &electrode_currents(&options.geometry, &reported, options.photocurrent_a)
                    .apply_gains(&gains),
                gain_x1,
            );
            let amplitudes = match options.snr_db {
                None => clean,
                Some(snr) => options.chain.measure(&clean, Some(snr), rng)?,
            };
            let measured = impact_point(&options.geometry, &amplitudes)?;
            points.push(SimulatedPoint {
                led,
                ideal,
                true_measured,
                amplitudes,
                measured,
            });
        }
        images.push(SimulatedImage {
            id: format!("{}", i + 1),
            points,
        });
    }
    Ok(Simulation {
        options: options.clone(),
        truth,
        gains,
        gain_x1,
        poses,
        template,
        images,
    })
}

fn scale(a: &Amplitudes, k: f64) -> Amplitudes {
    Amplitudes {
        vx1: a.vx1 * k,
        vx2: a.vx2 * k,
        vy1: a.vy1 * k,
        vy2: a.vy2 * k,
    }
}

impl Simulation {
    /// RMS angle-of-arrival error (rad) of a calibrated `model` over held-out
    /// directions: a 9 × 9 grid of true ideal points over 80 % of the sensor,
    /// each measured through the true distortion and the true (possibly
    /// unbalanced) electronics without noise, corrected with `model` and
    /// compared with the true ray. Directions the truth cannot image are
    /// skipped. The error of a point is the angle between the two rays.
    pub fn aoa_rms_error(&self, model: &SensorModel, gains: &ChannelGains) -> f64 {
        let geometry = &self.options.geometry;
        let (mut sum, mut n) = (0.0, 0usize);
        let (estimate, truth) = (Model::standard(model), Model::standard(&self.truth));
        for i in 0..9 {
            for j in 0..9 {
                let ideal = Vector2::new(
                    0.4 * geometry.lx * (i as f64 / 4.0 - 1.0),
                    0.4 * geometry.ly * (j as f64 / 4.0 - 1.0),
                );
                let Ok(true_measured) = truth.measured_from_ideal_to_tolerance(&ideal) else {
                    continue;
                };
                let reported = if self.options.psd_nonlinearity {
                    PsdNonlinearity::new(*geometry).reported(&true_measured)
                } else {
                    true_measured
                };
                let amps = electrode_currents(geometry, &reported, 1.0).apply_gains(&self.gains);
                let Ok(measured) =
                    psdcal_model::psd::impact_point_with_gains(geometry, &amps, gains)
                else {
                    continue;
                };
                let est = estimate.direction(&measured);
                let want = truth.direction_of_ideal(&ideal);
                let angle = est.cross(&want).norm().atan2(est.dot(&want));
                sum += angle * angle;
                n += 1;
            }
        }
        if n == 0 {
            f64::INFINITY
        } else {
            (sum / n as f64).sqrt()
        }
    }
}
