//! What a calibration is asked ([`CalibrateOptions`]): the start's options,
//! the refinement's (cost, freed parameters, noise model, robust loss), the
//! global search over `l1`, the model's stages and fixed values (`base`), how
//! the covariance is estimated ([`Uncertainty`]), what the diagnostics may
//! use, and an optional prior; and the refinement's start built from them
//! (`base` with the freed `f, cx, cy, k1, k2` of the initialisation).

use psdcal_model::{Model, Param, ParameterCovariance, SensorModel};

use crate::diagnose::residual_structure::DiagnosticOptions;
use crate::refine::global::GlobalOptions;
use crate::refine::options::RefineOptions;
use crate::select::choose::ModelChoice;
use crate::start::initialize::InitOptions;
use crate::uncertainty::bootstrap::BootstrapOptions;
use crate::CalibError;

/// Options of [`calibrate`](fn@crate::calibrate).
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrateOptions {
    /// The start.
    pub init: InitOptions,
    /// The refinement (cost, freed parameters, robust loss, tolerances).
    pub refine: RefineOptions,
    /// The global search used when `l1` is freed.
    pub global: GlobalOptions,
    /// The model's stages and the values of the parameters that are not
    /// freed (the standard chain with zero distortion by default; a chain
    /// with more stages, e.g. a PSD map, carries them into the fit).
    pub base: Model,
    /// How the covariance is estimated (linear by default).
    pub uncertainty: Uncertainty,
    /// Whether the freed parameters are fitted as given (the library's
    /// default) or grown by held-out error ([`crate::select::choose`]).
    pub choice: ModelChoice,
    /// What the diagnostics may use beyond the fit (a known point noise).
    pub diagnostics: DiagnosticOptions,
    /// A Gaussian prior on parameters of `base` (a PSD map's coefficients
    /// with their scan's covariance), its mean their values in `base`:
    /// they are freed in a last refinement (module documentation). `None`
    /// by default.
    pub prior: Option<ParameterCovariance>,
    /// The covariance of a block of `base` held fixed (a PSD map's
    /// coefficients with their scan's covariance), carried into the
    /// estimate's after the fit (`C_θ + G C_m Gᵀ`, docs/model.md §8.3).
    /// Ignored with a [`Self::prior`], which frees the block. `None` by
    /// default.
    pub fixed_covariance: Option<ParameterCovariance>,
}

/// How [`calibrate`](fn@crate::calibrate) estimates the covariance
/// (calibration.json's provenance: `{"method": "linear"}` or
/// `{"method": "bootstrap", "resamples": N, "seed": S}` or
/// `{"method": "jackknife"}`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(tag = "method", rename_all = "kebab-case")]
pub enum Uncertainty {
    /// Analytic ([`mod@crate::covariance`]): the sandwich for the unweighted
    /// template-plane fit, `σ² (JᵀJ)⁻¹` otherwise.
    #[default]
    Linear,
    /// Case bootstrap by image ([`crate::bootstrap`]).
    Bootstrap(BootstrapOptions),
    /// The analytic σ, raised parameter by parameter to the jackknife over
    /// images from the linearisation when that is larger (residuals
    /// correlated within an image: the model misses something;
    /// [`crate::select::influence`], docs/model.md §4.6).
    Jackknife,
}

impl Default for CalibrateOptions {
    /// The paper's defaults: template-plane cost, `f, cx, cy, k1, k2` freed,
    /// every other parameter fixed at zero (`f` at 8 mm only matters if the
    /// user fixes it).
    fn default() -> Self {
        Self {
            init: InitOptions::default(),
            refine: RefineOptions::default(),
            global: GlobalOptions::default(),
            base: Model::standard(&SensorModel::pinhole(8.0, 0.0, 0.0)),
            uncertainty: Uncertainty::Linear,
            choice: ModelChoice::Given,
            diagnostics: DiagnosticOptions::default(),
            prior: None,
            fixed_covariance: None,
        }
    }
}

/// `options.base` seeded with the freed parameters the initialisation
/// estimates (`f, cx, cy, k1, k2`), taken from its chain `init_model`: what
/// the refinement starts from (`crate::refine::start_model` adds a gains
/// stage when the gains are freed).
pub(crate) fn seeded_base(
    options: &CalibrateOptions,
    init_model: &Model,
) -> Result<Model, CalibError> {
    let mut start = options.base.clone();
    for p in [Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2] {
        if options.refine.free.contains(&p) {
            if let Some(value) = init_model.get(p.name()) {
                start.set(p.name(), value)?;
            }
        }
    }
    // A fixed f, cx or cy must have been given; the poses come from the start.
    start.validate()?;
    Ok(start)
}
