//! `psdcal export`: a calibration as an OpenCV, mrcal or ROS camera model
//! (the work is `psdcal::export`).

use std::path::PathBuf;

use clap::Args;

use crate::messages::Output;

/// A calibration as an OpenCV, mrcal or ROS camera model (fitted, with its error)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct ExportArgs {
    /// Calibration written by psdcal (calibration.json)
    #[arg(long, short = 'c', value_name = "FILE")]
    pub calibration: PathBuf,
    /// Format: opencv, mrcal or ros
    #[arg(long, value_name = "FORMAT", value_enum)]
    pub to: psdcal::ExportTarget,
    /// Pixel pitch, µm (it must divide the active area's sides)
    #[arg(long, value_name = "UM", default_value_t = psdcal::DEFAULT_PIXEL_UM)]
    pub pixel_um: f64,
    /// Largest angle error of the converted model accepted, degrees
    #[arg(long, value_name = "DEG", default_value_t = psdcal::DEFAULT_MAX_ERROR_DEG)]
    pub max_error_deg: f64,
    /// Where to write the camera model (atomically)
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// Runs `export`.
pub fn run(args: &ExportArgs, output: Output, limits: psdcal::ReadLimits) -> anyhow::Result<()> {
    let done = psdcal::export(&psdcal::ExportRequest {
        calibration: args.calibration.clone(),
        target: args.to,
        pixel_um: args.pixel_um,
        max_error_deg: args.max_error_deg,
        out: args.out.clone(),
        limits,
    })?;
    let summary = psdcal::Summary::new(done.summary(), done.to_json());
    crate::messages::emit(output, &summary.warn(&done.warnings))
}
