//! What a calibration noticed about itself: a [`Diagnostic`] with a stable
//! [`DiagnosticCode`] (docs/formats.md, "Diagnostic codes"), a
//! [`Severity`] and a message. Defined here, below psdcal-calib (which
//! computes them) and psdcal-io (which stores them in calibration.json's
//! `diagnostics`), so that both use one type.

use serde::{Deserialize, Serialize};

/// The stable identifier of a diagnostic; serialised in snake case
/// (`model_misfit`, …). Scripts may test these codes: they never change
/// meaning.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DiagnosticCode {
    /// The fit may have stopped in a local minimum.
    LocalMinimumSuspected,
    /// The model does not explain the data to the noise level.
    ModelMisfit,
    /// The residuals look like unequal channel gains (docs/model.md §1.3).
    GainImbalanceSuspected,
    /// The reported σ and covariance should not be trusted.
    UncertaintyUnreliable,
    /// Points fall where the measured → ideal map is not one-to-one
    /// (docs/model.md §8.2).
    OutsideValidRegion,
    /// `f` or the centre moves by more than 3σ with a group the model
    /// choice took: a model without it disagrees (docs/model.md §4.8).
    ModelDependent,
}

impl DiagnosticCode {
    /// Every code, in documentation order.
    pub const ALL: [DiagnosticCode; 6] = [
        DiagnosticCode::LocalMinimumSuspected,
        DiagnosticCode::ModelMisfit,
        DiagnosticCode::GainImbalanceSuspected,
        DiagnosticCode::UncertaintyUnreliable,
        DiagnosticCode::OutsideValidRegion,
        DiagnosticCode::ModelDependent,
    ];

    /// The code as written in files and JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            DiagnosticCode::LocalMinimumSuspected => "local_minimum_suspected",
            DiagnosticCode::ModelMisfit => "model_misfit",
            DiagnosticCode::GainImbalanceSuspected => "gain_imbalance_suspected",
            DiagnosticCode::UncertaintyUnreliable => "uncertainty_unreliable",
            DiagnosticCode::OutsideValidRegion => "outside_valid_region",
            DiagnosticCode::ModelDependent => "model_dependent",
        }
    }
}

impl std::fmt::Display for DiagnosticCode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// How much a diagnostic matters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    /// Worth knowing; the result stands.
    Info,
    /// The result (or its uncertainty) is doubtful.
    Warning,
    /// The result should not be used (accepted in files; `calibrate`
    /// refuses such a fit with an error instead).
    Error,
}

impl Severity {
    /// The severity as written in files and JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            Severity::Info => "info",
            Severity::Warning => "warning",
            Severity::Error => "error",
        }
    }
}

/// Something a calibration noticed about itself.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Diagnostic {
    /// Stable identifier.
    pub code: DiagnosticCode,
    /// How much it matters.
    pub severity: Severity,
    /// What it means for this calibration (one line).
    pub message: String,
}

impl Diagnostic {
    /// A diagnostic of severity `warning`.
    pub fn warning(code: DiagnosticCode, message: impl Into<String>) -> Self {
        Self {
            code,
            severity: Severity::Warning,
            message: message.into(),
        }
    }

    /// A diagnostic of severity `info`.
    pub fn info(code: DiagnosticCode, message: impl Into<String>) -> Self {
        Self {
            code,
            severity: Severity::Info,
            message: message.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_serialise_as_their_stable_names() {
        for code in DiagnosticCode::ALL {
            let text = serde_json::to_string(&code).unwrap();
            assert_eq!(text, format!("\"{}\"", code.as_str()));
            let back: DiagnosticCode = serde_json::from_str(&text).unwrap();
            assert_eq!(back, code);
        }
        let d = Diagnostic::info(DiagnosticCode::ModelMisfit, "m");
        assert_eq!(
            serde_json::to_value(&d).unwrap(),
            serde_json::json!({"code": "model_misfit", "severity": "info", "message": "m"})
        );
        assert!(serde_json::from_str::<Severity>("\"error\"").is_ok());
        assert!(serde_json::from_str::<DiagnosticCode>("\"nonsense\"").is_err());
    }
}
