//! `psdcal focal-check`: the focal length from the measured corners of a
//! rectangle of known size at a known distance (the paper's Eq. 44) against
//! a calibration's (the work is `psdcal::focal_check`).

use std::path::PathBuf;

use crate::messages::Output;
use clap::Args;
use psdcal::option_text::{parse_sides_mm, positive_mm};

/// Check the focal length against a square of known size at a known distance (Eq. 44)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct FocalCheckArgs {
    /// The calibration to check (calibration.json)
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// The measured corners, in order around the rectangle (corner,x_mm,y_mm[,sigma_mm])
    #[arg(long, value_name = "FILE")]
    pub points: PathBuf,
    /// Distance of the rectangle's plane (parallel to the sensor), mm
    #[arg(long, value_name = "MM", value_parser = positive_mm)]
    pub distance: f64,
    /// Standard deviation of that distance, mm
    #[arg(long, value_name = "MM", default_value_t = 0.0)]
    pub distance_sigma: f64,
    /// Side of the square in the scene, mm (WxH for a rectangle: W from corner 1 to 2)
    #[arg(long, value_name = "MM", value_parser = parse_sides_mm)]
    pub size: (f64, f64),
}

/// Runs `focal-check`.
pub fn run(a: &FocalCheckArgs, output: Output, limits: psdcal::ReadLimits) -> anyhow::Result<()> {
    let check = psdcal::focal_check(&psdcal::FocalCheckRequest {
        calibration: a.calibration.clone(),
        points: a.points.clone(),
        distance_mm: a.distance,
        distance_sigma_mm: a.distance_sigma,
        size_mm: a.size,
        limits,
    })?;
    let summary = psdcal::Summary::new(check.text.clone(), check.json.clone());
    crate::messages::emit(output, &summary)
}
