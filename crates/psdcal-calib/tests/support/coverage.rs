//! Coverage of the reported uncertainty (issue 12, point 4): seeded trials
//! in wide conditions, each calibrated with `calibrate` (default fit `f, cx,
//! cy, k1, k2`; the PSD's `l1` known, i.e. held at its true value, so that
//! the model can fit the data), and the error of every freed parameter in
//! units of its reported σ.
//!
//! Two kinds of trial:
//! - a **wide** trial is `WideScenario::draw(index)` as drawn (its own
//!   noise, 30 dB to noise-free and beyond);
//! - a **hard** trial re-noises the geometry of a fixed wide scenario (the
//!   first of the lens with 9–12 images) with Gaussian noise of a given σ
//!   from `ChaCha8Rng::seed_from_u64(HARD_SEED_BASE + trial)`.

use nalgebra::Vector2;
use psdcal_calib::covariance::{covariance_with, CovarianceMethod};
use psdcal_calib::{calibrate, CalibrateOptions, CalibrationData, CalibrationResult};
use psdcal_model::{DiagnosticCode, Model, Param, SensorModel};
use psdcal_testkit::wide::Lens;
use psdcal_testkit::WideScenario;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use super::wide::data;

/// The base of the hard trials' noise seeds.
pub const HARD_SEED_BASE: u64 = 0x00c0_5e00_0000;

/// The freed parameters (the default fit).
pub const FREE: [Param; 5] = [Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2];

/// Calibration options: the default fit with `l1` held at `truth`'s value.
pub fn options(truth: &SensorModel) -> CalibrateOptions {
    let mut base = SensorModel::pinhole(8.0, 0.0, 0.0);
    base.distortion.l1 = truth.distortion.l1;
    CalibrateOptions {
        base: Model::standard(&base),
        ..CalibrateOptions::default()
    }
}

/// The index of the first wide scenario of `lens` with 9–12 images, noisy
/// or not (its geometry is what a hard trial keeps).
pub fn hard_geometry(lens: Lens) -> u64 {
    (0..)
        .find(|&i| {
            let s = WideScenario::draw(i);
            s.lens == lens && (9..=12).contains(&s.images.len())
        })
        .expect("some scenario fits")
}

/// Scenario `index`'s data with its points replaced by the noise-free
/// projections plus Gaussian noise of `sigma_mm` drawn from `seed`
/// (image by image, point by point, x then y).
pub fn renoised(s: &WideScenario, sigma_mm: f64, seed: u64) -> CalibrationData {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut d = data(s);
    let truth = psdcal_model::Model::standard(&s.truth);
    for (image, wide) in d.images.iter_mut().zip(&s.images) {
        for obs in &mut image.points {
            let exact = truth
                .project_to_tolerance(&wide.view.pose, &s.template[obs.led])
                .expect("a wide scenario's point projects");
            let dx: f64 = rng.sample(StandardNormal);
            let dy: f64 = rng.sample(StandardNormal);
            obs.measured = exact + sigma_mm * Vector2::new(dx, dy);
        }
    }
    d
}

/// One calibrated trial: per freed parameter, the error and the reported σ.
#[derive(Debug, Clone)]
pub struct Trial {
    /// Which trial (the wide index, or the hard trial number).
    pub index: u64,
    /// Lens 1 or 2.
    pub lens: u8,
    /// The point noise, mm.
    pub sigma_mm: f64,
    /// Images.
    pub images: usize,
    /// Per freed parameter: estimate − truth.
    pub errors: Vec<f64>,
    /// Per freed parameter: the reported σ.
    pub std: Vec<f64>,
    /// Per freed parameter: σ by `σ² (JᵀJ)⁻¹` with one σ² (the estimate
    /// psdcal reported before the sandwich), for comparison.
    pub std_linear: Vec<f64>,
    /// The calibration, or why it failed.
    pub result: Result<CalibrationResult, String>,
}

impl Trial {
    /// Calibrates `data` (truth `s.truth`) with `options(&s.truth)` adjusted by `adjust`.
    pub fn run(
        index: u64,
        s: &WideScenario,
        sigma_mm: f64,
        data: &CalibrationData,
        adjust: impl Fn(&mut CalibrateOptions),
    ) -> Self {
        let mut o = options(&s.truth);
        adjust(&mut o);
        let result = calibrate(data, &o).map_err(|e| e.to_string());
        let (errors, std) = match &result {
            Ok(r) => FREE
                .iter()
                .map(|p| {
                    let est = r.model.get(p.name()).unwrap_or(f64::NAN);
                    (
                        est - s.truth.get(*p),
                        r.covariance.std(p.name()).unwrap_or(f64::NAN),
                    )
                })
                .unzip(),
            Err(_) => (vec![], vec![]),
        };
        let std_linear = match &result {
            Ok(r) => {
                let refined = r.refined();
                covariance_with(data, &refined, &o.refine, CovarianceMethod::Linear).map_or_else(
                    |_| vec![f64::NAN; FREE.len()],
                    |c| {
                        FREE.iter()
                            .map(|p| c.std(p.name()).unwrap_or(f64::NAN))
                            .collect()
                    },
                )
            }
            Err(_) => vec![],
        };
        Self {
            std_linear,
            index,
            lens: s.lens.number(),
            sigma_mm,
            images: s.images.len(),
            errors,
            std,
            result,
        }
    }

    /// |error| / σ per freed parameter (empty when the calibration failed).
    pub fn z(&self) -> Vec<f64> {
        self.errors
            .iter()
            .zip(&self.std)
            .map(|(e, s)| (e / s).abs())
            .collect()
    }

    /// Whether the calibration says its σ is not to be taken as a 3σ
    /// statement: `uncertainty_unreliable` (conditioning, or the ±3σ
    /// curvature confirmed by the profile), or `model_misfit` (the model
    /// does not explain the data, e.g. a wrong minimum: its σ says nothing
    /// of the truth). A failed calibration is not flagged (no σ to judge).
    pub fn flagged(&self) -> bool {
        self.result.as_ref().is_ok_and(|r| {
            r.diagnostics.iter().any(|d| {
                matches!(
                    d.code,
                    DiagnosticCode::UncertaintyUnreliable | DiagnosticCode::ModelMisfit
                )
            })
        })
    }

    /// |error| / σ_linear per freed parameter.
    pub fn z_linear(&self) -> Vec<f64> {
        self.errors
            .iter()
            .zip(&self.std_linear)
            .map(|(e, s)| (e / s).abs())
            .collect()
    }
}

/// The fraction of `z` values at or below `k` (NaN counts as a miss).
pub fn covered(z: &[f64], k: f64) -> f64 {
    z.iter().filter(|v| **v <= k).count() as f64 / z.len().max(1) as f64
}
