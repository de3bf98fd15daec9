//! Simulated calibration scenarios (docs/model.md §7 and the paper's Section 4.1):
//! the lens, the template, the template poses and the electronics, all drawn
//! from one seed.
//!
//! *Lenses*: the paper's lens 1 (f = 25 mm, k1 = 2e-3 mm⁻²) and lens 2
//! (f = 8 mm, k1 = 1e-2 mm⁻², k2 = 3e-5 mm⁻⁴), optical centre (0.5, −0.7) mm;
//! optionally the PSD's own distortion `l1 = −1.3058e-3 mm⁻²` (Section 4.5).
//!
//! *Templates* (the paper gives no coordinates, so psdcal fixes its own):
//! `scatter14`, 14 LEDs within ±150 mm with no three collinear (the paper's
//! "unaligned" template), and `grid`, 5 × 5 LEDs 70 mm apart declaring its
//! rows and columns as lines (for the line-straightness correction).
//!
//! *Poses* (`sensor_from_template`): the template's centre is aimed at a
//! jittered 3 × 3 grid of sensor positions (cycled for more than nine images,
//! jitter ±0.5 mm) so that the images together cover the sensor; the distance
//! is uniform in `[70, 150] × f` (0.56–1.2 m for lens 2, 1.75–3.75 m for lens
//! 1: the template's image then spans about a third of the sensor for either
//! lens); the tilt is uniform up to 30° about a uniformly drawn axis in the
//! template plane, then any roll. A pose is redrawn until every LED falls
//! inside the active area with a 0.1 mm margin.
//!
//! *Gain imbalance* (P43): each channel's transimpedance gain
//! `K = R / (2π f R C + 1)` at f = 13.793 kHz (the paper's worst case) with
//! `R ~ U[100 kΩ (1 ± 1 %)]`, `C ~ U[100 pF (1 ± 15 %)]`; the relative gains
//! `g_k = K_k / K_x1` are what biases the impact point.

use nalgebra::{Vector2, Vector3};
use psdcal_model::psd::transimpedance_gain;
use psdcal_model::{ChannelGains, Model, Pose, PsdGeometry, SensorModel};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// Nominal transimpedance resistor (P43), Ω.
pub const NOMINAL_R_OHM: f64 = 100e3;
/// Nominal transimpedance capacitor (P43), F.
pub const NOMINAL_C_FARAD: f64 = 100e-12;
/// Frequency at which the paper evaluates the gain spread (P43), Hz.
pub const IMBALANCE_FREQUENCY_HZ: f64 = 13.793e3;
/// Resistor tolerance (uniform), relative.
pub const R_TOLERANCE: f64 = 0.01;
/// Capacitor tolerance (uniform), relative.
pub const C_TOLERANCE: f64 = 0.15;
/// Most redraws of one pose before the scenario is declared impossible.
const MAX_POSE_DRAWS: usize = 10_000;

/// One of the paper's two lenses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub enum Lens {
    /// f = 25 mm, k1 = 2e-3 mm⁻².
    One,
    /// f = 8 mm, k1 = 1e-2 mm⁻², k2 = 3e-5 mm⁻⁴.
    Two,
}

/// The command line's `--lens 1|2` (no help per value).
#[cfg(feature = "clap")]
impl clap::ValueEnum for Lens {
    fn value_variants<'a>() -> &'a [Self] {
        &[Lens::One, Lens::Two]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(match self {
            Lens::One => "1",
            Lens::Two => "2",
        }))
    }
}

impl Lens {
    /// The lens's true model (no PSD distortion).
    pub fn model(self) -> SensorModel {
        match self {
            Lens::One => SensorModel::paper_lens1(),
            Lens::Two => SensorModel::paper_lens2(),
        }
    }

    /// 1 or 2.
    pub fn number(self) -> u8 {
        match self {
            Lens::One => 1,
            Lens::Two => 2,
        }
    }
}

/// The calibration template.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum TemplateKind {
    /// 14 unaligned LEDs.
    Scatter14,
    /// 5 × 5 grid with its rows and columns declared as lines.
    Grid,
}

/// A template: LED positions (mm) and collinear groups.
#[derive(Debug, Clone, PartialEq)]
pub struct Template {
    /// LED `(X, Y)`, mm.
    pub leds: Vec<Vector2<f64>>,
    /// Collinear groups (indices into `leds`).
    pub lines: Vec<Vec<usize>>,
    /// Each group's label (`r1`…, `c1`…), for template.csv.
    pub line_names: Vec<String>,
}

/// The 14 unaligned LEDs of `scatter14`, mm (defined once, in
/// [`psdcal_model::paper_setup`]).
pub use psdcal_model::paper_setup::SCATTER14_MM;

impl TemplateKind {
    /// The template's LEDs and lines.
    pub fn template(self) -> Template {
        match self {
            TemplateKind::Scatter14 => Template {
                leds: psdcal_model::paper_setup::scatter14(),
                lines: Vec::new(),
                line_names: Vec::new(),
            },
            TemplateKind::Grid => {
                let leds = (0..25)
                    .map(|k| {
                        Vector2::new(
                            -140.0 + 70.0 * (k % 5) as f64,
                            -140.0 + 70.0 * (k / 5) as f64,
                        )
                    })
                    .collect();
                let rows = (0..5).map(|r| (0..5).map(|c| r * 5 + c).collect());
                let cols = (0..5).map(|c| (0..5).map(|r| r * 5 + c).collect());
                Template {
                    leds,
                    lines: rows.chain(cols).collect(),
                    line_names: (1..=5)
                        .map(|r| format!("r{r}"))
                        .chain((1..=5).map(|c| format!("c{c}")))
                        .collect(),
                }
            }
        }
    }

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TemplateKind::Scatter14 => "scatter14",
            TemplateKind::Grid => "grid",
        }
    }
}

/// Draws the relative channel gains of an imbalanced amplifier stage (P43).
pub fn draw_imbalance(rng: &mut ChaCha8Rng) -> ChannelGains {
    let mut k = [0.0; 4];
    for kk in &mut k {
        let r = NOMINAL_R_OHM * (1.0 + rng.random_range(-R_TOLERANCE..=R_TOLERANCE));
        let c = NOMINAL_C_FARAD * (1.0 + rng.random_range(-C_TOLERANCE..=C_TOLERANCE));
        *kk = transimpedance_gain(r, c, IMBALANCE_FREQUENCY_HZ);
    }
    ChannelGains::from_absolute(k[0], k[1], k[2], k[3])
}

/// Draws `n` template poses for a sensor `truth` (module documentation).
/// Returns `None` when no admissible pose is found (a template too large for
/// the sensor at these distances).
pub fn draw_poses(
    truth: &SensorModel,
    geometry: &PsdGeometry,
    template: &Template,
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Option<Vec<Pose>> {
    let f = truth.intrinsics.f;
    let (half_x, half_y) = (0.5 * geometry.lx, 0.5 * geometry.ly);
    let model = Model::standard(truth);
    let mut poses = Vec::with_capacity(n);
    while poses.len() < n {
        let k = poses.len() % 9;
        let mut found = None;
        for _ in 0..MAX_POSE_DRAWS {
            let aim = Vector2::new(
                (-0.55 + 0.55 * (k % 3) as f64) * half_x + rng.random_range(-0.5..0.5),
                (-0.55 + 0.55 * (k / 3) as f64) * half_y + rng.random_range(-0.5..0.5),
            );
            let z = f * rng.random_range(70.0..150.0);
            let tilt = rng.random_range(0.0..30f64.to_radians());
            let axis = rng.random_range(0.0..std::f64::consts::TAU);
            let roll = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
            let tilt_pose = Pose::new(
                Vector3::new(axis.cos(), axis.sin(), 0.0) * tilt,
                Vector3::zeros(),
            );
            let roll_pose = Pose::new(Vector3::new(0.0, 0.0, roll), Vector3::zeros());
            let rvec = tilt_pose.compose(&roll_pose).rvec;
            let t = Vector3::new(
                (aim.x - truth.intrinsics.cx) * z / f,
                (aim.y - truth.intrinsics.cy) * z / f,
                z,
            );
            let pose = Pose::new(rvec, t);
            let inside = template.leds.iter().all(|xy| {
                model
                    .project_to_tolerance(&pose, xy)
                    .is_ok_and(|m| m.x.abs() <= half_x - 0.1 && m.y.abs() <= half_y - 0.1)
            });
            if inside {
                found = Some(pose);
                break;
            }
        }
        poses.push(found?);
    }
    Some(poses)
}
