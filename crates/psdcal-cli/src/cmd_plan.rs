//! `psdcal plan`: template poses that minimise the predicted AoA σ, as
//! poses.csv (the work is `psdcal::plan_poses`).

use std::path::PathBuf;

use crate::messages::Output;
use anyhow::Result;
use clap::Args;
use psdcal::option_text::{
    parse_assignment, parse_fit, parse_images, parse_range_mm, parse_sides_mm, parse_snr,
    positive_mm, FitList,
};
use psdcal::ReadLimits;

/// Plan template poses that minimise the predicted angle-of-arrival uncertainty (poses.csv)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct PlanArgs {
    /// Nominal focal length, mm (not with --next)
    #[arg(long, value_name = "MM", value_parser = positive_mm, required_unless_present = "next")]
    pub f: Option<f64>,
    /// The template (template.csv)
    #[arg(long, value_name = "FILE")]
    pub template: PathBuf,
    /// Per-channel SNR of the records, dB
    #[arg(long, value_name = "DB", value_parser = parse_snr, allow_negative_numbers = true)]
    pub snr: f64,
    /// Number of poses, at least 3
    #[arg(long, value_name = "N", default_value = "9", value_parser = parse_images)]
    pub images: usize,
    /// Active area LXxLY, mm
    #[arg(long, value_name = "LXxLY", default_value = "9x9", value_parser = parse_sides_mm)]
    pub sensor: (f64, f64),
    /// Distance range of the template's centre MIN:MAX, mm (default: any that keeps it on the area)
    #[arg(long, value_name = "MIN:MAX", value_parser = parse_range_mm)]
    pub distance: Option<(f64, f64)>,
    /// Largest tilt of the template from facing the sensor, degrees
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 45.0,
        allow_negative_numbers = true
    )]
    pub tilt_max: f64,
    /// Margin kept between every LED and the active area's edge, mm
    #[arg(long, value_name = "MM", default_value_t = 0.2)]
    pub margin: f64,
    /// Parameters the calibration will estimate (default f,cx,cy,k1,k2; 'gains' adds the channel gains)
    #[arg(long, value_name = "LIST", value_parser = parse_fit)]
    pub fit: Option<FitList>,
    /// Nominal value of another parameter, e.g. k1=1e-2 (repeatable)
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_assignment)]
    pub set: Vec<(psdcal::Param, f64)>,
    /// Minimise the largest AoA sigma over the area instead of its RMS
    #[arg(long)]
    pub minimise_max: bool,
    /// Seed of the candidate poses
    #[arg(long, value_name = "S", default_value = "1")]
    pub seed: u64,
    /// Plan the single next pose for the calibration of --calibration
    #[arg(long, requires = "calibration")]
    pub next: bool,
    /// The current calibration (with --next)
    #[arg(long, value_name = "FILE", requires = "next")]
    pub calibration: Option<PathBuf>,
    /// poses.csv to write
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Folder for the AoA sigma heat map (plan_sigma.svg, plan_sigma.png)
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// Runs `plan`.
pub fn run(a: &PlanArgs, output: Output, limits: ReadLimits, force: bool) -> Result<()> {
    let planned = psdcal::plan_poses(&psdcal::PlanRequest {
        f_mm: a.f,
        template: a.template.clone(),
        snr_db: a.snr,
        images: a.images,
        geometry: psdcal::PsdGeometry {
            lx: a.sensor.0,
            ly: a.sensor.1,
        },
        distance_mm: a.distance,
        tilt_max_deg: a.tilt_max,
        margin_mm: a.margin,
        fit: a.fit.clone(),
        set: a.set.clone(),
        minimise_max: a.minimise_max,
        seed: a.seed,
        next: a.calibration.clone().filter(|_| a.next),
        out: a.out.clone(),
        report: a.report.clone(),
        limits,
        force,
    })?;
    let summary = psdcal::Summary::new(planned.text.clone(), planned.json.clone());
    crate::messages::emit(output, &summary)
}
