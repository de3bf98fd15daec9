//! `psdcal aoa`: angles of arrival of measured points (or electrode
//! amplitudes) with their uncertainty (the library's `aoa_table`).

use crate::cli_locate::AoaArgs;
use crate::messages::Output;

/// Runs `aoa`.
pub fn run(args: &AoaArgs, output: Output, limits: psdcal::ReadLimits) -> anyhow::Result<()> {
    let out = args.out.as_deref();
    let sigma = args.point_sigma;
    let table = psdcal::aoa_table(&args.calibration, &args.points, sigma, out, limits)?;
    let extra = serde_json::json!({ "point_sigma_mm": args.point_sigma });
    let summary = table
        .answer
        .summary("aoa", "aoa:", &args.calibration, out, extra, false);
    let summary = summary.warn(psdcal::covariance_warning(&table.sensor));
    crate::messages::emit(output, &summary)
}
