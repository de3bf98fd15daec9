//! A calibration's result as plain values for printing: what the command
//! line's summary and any other front end show, and its text.

use std::fmt;

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
    /// What the fit noticed about itself, with stable codes (docs/formats.md;
    /// calibration.json's `diagnostics`).
    pub diagnostics: Vec<psdcal_model::Diagnostic>,
    /// How σ was computed (`jackknife`, `linear`, …).
    pub uncertainty: &'static str,
    /// The model choice, when `calibrate` chose the freed parameters.
    pub model_choice: Option<ChoiceRows>,
}

/// One candidate: freed parameters, score statistic, (held-out RMS, mean
/// log ratio, standard error) when refitted, taken.
pub type CandidateRow = (String, Option<f64>, Option<(f64, f64, f64)>, bool);

/// The model choice's candidates (docs/model.md §4.8).
#[derive(Debug, Clone, PartialEq)]
pub struct ChoiceRows {
    /// Per candidate, in the order tried: its freed parameters, its score
    /// statistic, when refitted its RMS held-out angle error (degrees) and
    /// the mean per-image log ratio of squared held-out angles against the
    /// set it was compared with with its standard error, whether it was
    /// taken.
    pub candidates: Vec<CandidateRow>,
    /// The chosen freed parameters.
    pub chosen: String,
    /// Why no candidate was scored, when none was.
    pub skipped: Option<String>,
}

impl fmt::Display for FitReport {
    /// The summary `psdcal calibrate` prints (without its `wrote` lines).
    fn fmt(&self, out: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = self;
        writeln!(
            out,
            "calibrated {} images, {} points; start: {}",
            r.images, r.points, r.start
        )?;
        if let Some(reason) = &r.closed_form_rejection {
            writeln!(out, "  closed form not used: {reason}")?;
        }
        writeln!(out)?;
        writeln!(out, "parameter          value           std    unit")?;
        for p in &r.parameters {
            match p.std {
                Some(sd) => writeln!(
                    out,
                    "{:<9} {:>15.8e} ± {:<11.3e} {}",
                    p.name, p.value, sd, p.unit
                )?,
                None if p.value != 0.0 => writeln!(
                    out,
                    "{:<9} {:>15.8e}   (fixed)     {}",
                    p.name, p.value, p.unit
                )?,
                None => {}
            }
        }
        if !r.gains.is_empty() {
            for (name, value, s) in &r.gains {
                writeln!(out, "{name:<9} {value:>15.8e} ± {s:<11.3e} (relative gain)")?;
            }
            if let Some(start) = &r.gain_start {
                writeln!(out, "gain start: {start}")?;
            }
        }
        writeln!(out)?;
        if !r.correlation_names.is_empty() {
            write!(out, "correlation")?;
            for name in &r.correlation_names {
                write!(out, " {name:>6}")?;
            }
            writeln!(out)?;
            for (i, name) in r.correlation_names.iter().enumerate() {
                write!(out, "{name:<11}")?;
                for value in r.correlation[i].iter().take(i + 1) {
                    write!(out, " {value:>+6.3}")?;
                }
                writeln!(out)?;
            }
            writeln!(out)?;
        }
        writeln!(
            out,
            "cost minimised:   {}{}{}",
            r.cost,
            if r.robust { " (robust)" } else { "" },
            r.noise.map_or(String::new(), |n| format!(
                ", weighted by the {n} noise model"
            ))
        )?;
        writeln!(
            out,
            "residual:         {:.6e} mm² (sum of squared template-plane errors)",
            r.residual_mm2
        )?;
        writeln!(
            out,
            "RMS error:        {:.4e} mm on the template, {:.4e} mm on the sensor",
            r.rms_template_mm, r.rms_image_mm
        )?;
        writeln!(
            out,
            "iterations:       {} ({})",
            r.iterations, r.termination
        )?;
        writeln!(
            out,
            "σ:                {}",
            uncertainty_words(r.uncertainty)
        )?;
        if let Some(choice) = &r.model_choice {
            write_choice(out, choice)?;
        }
        if let Some(g) = &r.global {
            writeln!(
                out,
                "l1 search:        {} minima found, {} refinements",
                g.minima.len(),
                g.refinements
            )?;
            for [cost, l1, k1, f] in &g.minima {
                writeln!(
                    out,
                    "                  cost {cost:.6e} at l1 = {l1:.4e}, k1 = {k1:.4e}, f = {f:.4}"
                )?;
            }
        }
        writeln!(out)?;
        writeln!(out, "image   points   RMS template (mm)   RMS sensor (mm)")?;
        for i in &r.per_image {
            writeln!(
                out,
                "{:<7} {:>6}   {:>17.4e}   {:>15.4e}",
                i.id, i.points, i.rms_template_mm, i.rms_image_mm
            )?;
        }
        writeln!(out)
    }
}

/// The σ method in words.
fn uncertainty_words(method: &str) -> String {
    match method {
        "jackknife" => "linear, raised to the jackknife over images where that is larger".into(),
        "linear" => "linear (from the fit's linearisation and its residual noise)".into(),
        other => other.to_string(),
    }
}

/// The model choice's table.
fn write_choice(out: &mut fmt::Formatter<'_>, choice: &ChoiceRows) -> fmt::Result {
    if let Some(reason) = &choice.skipped {
        return writeln!(
            out,
            "model:            {} (no choice by held-out error: {reason})",
            choice.chosen
        );
    }
    writeln!(
        out,
        "model chosen:     {} (by leave-one-image-out angle error)",
        choice.chosen
    )?;
    writeln!(
        out,
        "  {:<34} {:>8} {:>12}   {:>22}",
        "candidate", "score", "held-out", "ln ratio per image"
    )?;
    for (k, (free, lm, held_out, taken)) in choice.candidates.iter().enumerate() {
        let lm = lm.map_or_else(String::new, |v| format!("{v:.1}"));
        let (rms, delta) = match held_out {
            Some((rms, _, _)) if k == 0 => (format!("{rms:.5}°"), "base".to_string()),
            Some((rms, l, se)) => (format!("{rms:.5}°"), format!("{l:+.3} ± {se:.3}")),
            None => (String::new(), "not refitted (score)".to_string()),
        };
        let mark = if *taken && k > 0 { "  taken" } else { "" };
        writeln!(out, "  {free:<34} {lm:>8} {rms:>12}   {delta:>22}{mark}")?;
    }
    Ok(())
}
