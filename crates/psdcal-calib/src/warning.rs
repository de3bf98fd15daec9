//! What a fit warns about without refusing it, as types: each warning's
//! text (its `Display`) is what the command line prints after `warning:`
//! and what calibration.json's summary lists; code decides by variant, not
//! by text.

use std::fmt;

/// A warning of a calibration (planar or surveyed).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum FitWarning {
    /// A parameter's variance is inflated by its correlation with the
    /// others beyond [`crate::covariance::INFLATION_WARNING`].
    PoorlyDetermined {
        /// The parameter.
        parameter: String,
        /// `(S⁻¹)_kk S_kk`.
        inflation: f64,
    },
    /// Two parameters correlated beyond
    /// [`crate::covariance::CORRELATION_WARNING`].
    StronglyCorrelated {
        /// The first parameter.
        first: String,
        /// The second parameter.
        second: String,
        /// Their correlation.
        correlation: f64,
    },
    /// The automatic preliminary correction failed and was skipped.
    PreliminarySkipped {
        /// Why it failed.
        reason: String,
    },
    /// Points down-weighted as outliers by the robust loss.
    Outliers {
        /// How many.
        count: usize,
    },
    /// The global search over `l1` found several minima.
    LocalMinima {
        /// How many.
        count: usize,
        /// The lowest cost (kept).
        lowest: f64,
        /// The next cost.
        next: f64,
    },
    /// A surveyed fit's residuals are smaller than the stated survey σ
    /// predicts.
    SurveyBetterThanStated {
        /// The residual cost, mm².
        residual_mm2: f64,
        /// The stated survey σ, mm.
        survey_sigma_mm: f64,
        /// The cost the survey σ predicts, mm².
        predicted_mm2: f64,
    },
}

impl fmt::Display for FitWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FitWarning::PoorlyDetermined {
                parameter,
                inflation,
            } => write!(
                f,
                "{parameter} is poorly determined by these images (variance inflated \
                 {inflation:.1e}× by correlation with the other parameters); consider fixing it"
            ),
            FitWarning::StronglyCorrelated {
                first,
                second,
                correlation,
            } => write!(
                f,
                "{first} and {second} are strongly correlated ({correlation:+.3}): the data \
                 barely separate them"
            ),
            FitWarning::PreliminarySkipped { reason } => {
                write!(f, "automatic preliminary correction skipped: {reason}")
            }
            FitWarning::Outliers { count } => write!(
                f,
                "{count} point(s) down-weighted as outliers by the robust loss"
            ),
            FitWarning::LocalMinima {
                count,
                lowest,
                next,
            } => write!(
                f,
                "the cost has {count} local minima over l1; the lowest ({lowest:.4e}) was kept, \
                 the next is {next:.4e}"
            ),
            FitWarning::SurveyBetterThanStated {
                residual_mm2,
                survey_sigma_mm,
                predicted_mm2,
            } => write!(
                f,
                "the residuals ({residual_mm2:.3e} mm²) are smaller than a survey σ of \
                 {survey_sigma_mm} mm predicts ({predicted_mm2:.3e} mm²): the survey is better \
                 than stated, and the reported uncertainty errs on the large side"
            ),
        }
    }
}

/// The warnings as text, in order.
pub fn warning_texts(warnings: &[FitWarning]) -> Vec<String> {
    warnings.iter().map(ToString::to_string).collect()
}
