//! `psdcal evaluate`: estimated positions (and angles) against a surveyed
//! truth by the standard metrics (the library's `evaluate`).

use std::path::PathBuf;

use clap::Args;

use crate::messages::Output;
use anyhow::Result;
use psdcal::ReadLimits;

/// Judge estimated positions against a surveyed truth (mean, RMS, 75th/95th percentiles, CE95, SE95, honest error bars)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct EvaluateArgs {
    /// Surveyed truth: emitter, x_mm, y_mm, z_mm (and/or alpha_x_deg, alpha_y_deg)
    #[arg(long, value_name = "FILE")]
    pub truth: PathBuf,
    /// Estimates to judge: the CSV psdcal locate (or aoa) writes, with an emitter column
    #[arg(long, value_name = "FILE")]
    pub estimates: PathBuf,
    /// Rig file: plot the error against the distance to the nearest sensor
    #[arg(long, value_name = "FILE")]
    pub rig: Option<PathBuf>,
    /// Folder (created if missing) for evaluation.html and its figures (SVG)
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// Runs `evaluate`.
pub fn run(args: &EvaluateArgs, output: Output, limits: ReadLimits, force: bool) -> Result<()> {
    let evaluation = psdcal::evaluate(&psdcal::EvaluateRequest {
        truth: args.truth.clone(),
        estimates: args.estimates.clone(),
        rig: args.rig.clone(),
        limits,
    })?;
    let files = match &args.report {
        Some(dir) => evaluation.write_report(dir, force)?,
        None => Vec::new(),
    };
    crate::messages::emit(output, &evaluation.summary(&files))
}
