//! `psdcal correct`: measured points (or amplitudes) → ideal points, with
//! a status per row.

use crate::args::CorrectArgs;
use crate::messages::Output;

/// Runs `correct`.
pub fn run(args: &CorrectArgs, output: Output, limits: psdcal::ReadLimits) -> anyhow::Result<()> {
    let out = args.out.as_deref();
    let corrected = psdcal::correct(&args.calibration, &args.points, out, limits)?;
    let summary = corrected.answer.summary(
        "correct",
        "corrected",
        &args.calibration,
        out,
        serde_json::json!({}),
        true,
    );
    crate::messages::emit(output, &summary)
}
