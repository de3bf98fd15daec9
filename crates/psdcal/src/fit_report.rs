//! A calibration's result as plain values for printing: what the command
//! line's summary and any other front end show.

/// One sensor parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterRow {
    /// Name (`f`, `cx`, …).
    pub name: &'static str,
    /// Value.
    pub value: f64,
    /// Standard deviation when estimated.
    pub std: Option<f64>,
    /// Unit.
    pub unit: &'static str,
}

/// The global search over `l1`.
#[derive(Debug, Clone, PartialEq)]
pub struct GlobalSearch {
    /// Local minima: `[cost, l1, k1, f]`.
    pub minima: Vec<[f64; 4]>,
    /// Refinements run.
    pub refinements: usize,
}

/// One image's errors.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageRow {
    /// Identifier.
    pub id: String,
    /// Points used.
    pub points: usize,
    /// RMS template-plane error, mm.
    pub rms_template_mm: f64,
    /// RMS sensor error, mm.
    pub rms_image_mm: f64,
}

/// Everything the summary of a calibration shows.
#[derive(Debug, Clone, PartialEq)]
pub struct FitReport {
    /// Images calibrated.
    pub images: usize,
    /// Points used.
    pub points: usize,
    /// How the start was found.
    pub start: &'static str,
    /// Why the closed form was not used, if it was not.
    pub closed_form_rejection: Option<String>,
    /// Every sensor parameter, in `Param::ALL` order.
    pub parameters: Vec<ParameterRow>,
    /// Estimated relative gains: `(name, value, std)`.
    pub gains: Vec<(String, f64, f64)>,
    /// Which start won the gain estimation.
    pub gain_start: Option<String>,
    /// Names of the correlation matrix (empty with one free parameter).
    pub correlation_names: Vec<String>,
    /// The correlation matrix.
    pub correlation: Vec<Vec<f64>>,
    /// The cost minimised, in words.
    pub cost: &'static str,
    /// Whether a robust loss was used.
    pub robust: bool,
    /// The noise model's name when the cost was weighted.
    pub noise: Option<&'static str>,
    /// Sum of squared template-plane errors, mm².
    pub residual_mm2: f64,
    /// RMS template-plane error, mm.
    pub rms_template_mm: f64,
    /// RMS sensor error, mm.
    pub rms_image_mm: f64,
    /// Iterations.
    pub iterations: usize,
    /// Why the optimiser stopped.
    pub termination: String,
    /// The global search over `l1`, when it ran.
    pub global: Option<GlobalSearch>,
    /// Per image.
    pub per_image: Vec<ImageRow>,
    /// What the user should know.
    pub warnings: Vec<String>,
}
