//! The options of a calibration, as values and the option enums of the
//! crates that own them (never strings).

use psdcal_calib::{ModelChoice, NoiseModel, Preliminary, RobustLoss, Uncertainty};
use psdcal_model::{CostKind, Param};
use serde::Serialize;

/// Everything a calibration can be told.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CalibrationOptions {
    /// Parameters to estimate (the others stay fixed); with
    /// [`ModelChoice::HeldOut`] the base that groups are added to.
    pub free: Vec<Param>,
    /// Fit `free` as given, or grow it by held-out error (the default:
    /// `calibrate` without `--fit`; docs/model.md §4.8).
    pub choice: ModelChoice,
    /// Also estimate the amplifier gains (needs amplitudes).
    pub fit_gains: bool,
    /// Also estimate the y axis's own scale `a` (the aspect stage,
    /// docs/model.md §3.3).
    pub fit_aspect: bool,
    /// Values of fixed parameters.
    pub fixed: Vec<(Param, f64)>,
    /// Nominal focal length, mm (narrows the start's search).
    pub focal_guess: Option<f64>,
    /// The cost minimised.
    pub cost: CostKind,
    /// Its noise weighting.
    pub noise: NoiseModel,
    /// The preliminary correction.
    pub preliminary: Preliminary,
    /// Normalise the data of the homographies.
    pub normalize: bool,
    /// A robust loss.
    pub robust: Option<RobustLoss>,
    /// How the covariance is computed.
    pub uncertainty: Uncertainty,
    /// A PSD map (psd_map.json from `psdcal psd-map`) to put first in the
    /// model, held fixed (docs/model.md §8.3).
    pub psd_map: Option<std::path::PathBuf>,
    /// Refine the map's coefficients too, with its scan's covariance as
    /// their prior (docs/model.md §8.3); needs `psd_map`.
    pub refine_psd_map: bool,
}

impl Default for CalibrationOptions {
    /// The paper's: f, cx, cy, k1, k2 from automatic initialisation.
    fn default() -> Self {
        Self {
            free: vec![Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2],
            choice: ModelChoice::HeldOut,
            fit_gains: false,
            fit_aspect: false,
            fixed: Vec::new(),
            focal_guess: None,
            cost: CostKind::Template,
            noise: NoiseModel::Uniform,
            preliminary: Preliminary::Auto,
            normalize: true,
            robust: None,
            uncertainty: Uncertainty::Jackknife,
            psd_map: None,
            refine_psd_map: false,
        }
    }
}

impl CalibrationOptions {
    /// The options as JSON, for the provenance of calibration.json.
    pub fn to_json(&self) -> serde_json::Value {
        let mut v = serde_json::to_value(self).unwrap_or(serde_json::Value::Null);
        if let Some(map) = v.as_object_mut() {
            map.insert(
                "free".into(),
                self.free
                    .iter()
                    .map(|p| p.name())
                    .collect::<Vec<_>>()
                    .into(),
            );
            map.insert(
                "fixed".into(),
                self.fixed
                    .iter()
                    .map(|(p, x)| (p.name().to_string(), serde_json::json!(x)))
                    .collect::<serde_json::Map<_, _>>()
                    .into(),
            );
        }
        v
    }

    /// Checks that the options can work together; `with_amplitudes` says
    /// whether the data carry electrode amplitudes.
    pub fn check(&self, with_amplitudes: bool, known_gains: bool) -> Result<(), String> {
        if self.free.is_empty() {
            return Err("no parameter to estimate; free at least one, e.g. f,cx,cy,k1,k2".into());
        }
        if self.fit_gains && !with_amplitudes {
            return Err(
                "estimating the gains ('gains' in the fitted list) needs the electrode \
                        amplitudes: give signals.csv instead of observations"
                    .into(),
            );
        }
        if known_gains && !with_amplitudes {
            return Err(
                "known gains (gains.json) are divided out of the electrode amplitudes: \
                        give signals.csv instead of observations"
                    .into(),
            );
        }
        if self.fit_gains && known_gains {
            return Err(
                "known gains (gains.json) are held fixed: drop 'gains' from the fitted \
                        list, or drop the gains file"
                    .into(),
            );
        }
        if self.refine_psd_map && self.psd_map.is_none() {
            return Err("refining the PSD map needs the map: give --psd-map psd_map.json".into());
        }
        if let Some((p, _)) = self.fixed.iter().find(|(p, _)| self.free.contains(p)) {
            return Err(format!(
                "{p} is both fixed (set to a value) and estimated (in the fitted list); drop one \
                 of them"
            ));
        }
        Ok(())
    }
}
