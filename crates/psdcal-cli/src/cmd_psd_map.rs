//! `psdcal psd-map`: the PSD's non-linearity map from a lensless scan
//! (arguments and printing; the work is `psdcal::psd_map_from_scan`).

use std::path::PathBuf;

use clap::Args;
use psdcal::{PsdGeometry, PsdMapModel, PsdMapRequest};

use crate::messages::Output;
use anyhow::Result;
use psdcal::option_text::side_mm;
use psdcal::ReadLimits;

/// The PSD's own non-linearity map from a lensless scan (psd_map.json for calibrate --psd-map)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct PsdMapArgs {
    /// The scan: x_stage_mm, y_stage_mm, and x_mm, y_mm or vx1, vx2, vy1, vy2
    #[arg(long, value_name = "FILE")]
    pub scan: PathBuf,
    /// auto (cross-validated), poly:N (order N) or spline:N (N × N cells)
    #[arg(long, value_name = "MODEL", default_value = "auto", value_parser = psdcal::parse_psd_map_model)]
    pub model: PsdMapModel,
    /// Where to write psd_map.json (atomically)
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Active area side along x, mm
    #[arg(long, value_name = "MM", default_value = "9", value_parser = side_mm)]
    pub lx: f64,
    /// Active area side along y, mm
    #[arg(long, value_name = "MM", default_value = "9", value_parser = side_mm)]
    pub ly: f64,
    /// Seed of the cross-validation's folds
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,
    /// Folder for the report (psd_map.html, figures as SVG and PNG)
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// Runs `psd-map`.
pub fn run(args: &PsdMapArgs, output: Output, limits: ReadLimits, force: bool) -> Result<()> {
    let request = PsdMapRequest {
        scan: args.scan.clone(),
        model: args.model,
        geometry: PsdGeometry {
            lx: args.lx,
            ly: args.ly,
        },
        seed: args.seed,
        command: std::env::args().collect::<Vec<_>>().join(" "),
        report: args.report.clone(),
        limits,
        force,
    };
    let outcome = psdcal::psd_map_from_scan(&request)?;
    outcome.write(&args.out)?;
    let json = serde_json::to_value(&outcome.file)?;
    let summary = psdcal::Summary::new(outcome.text.clone(), json).wrote([args.out.as_path()]);
    crate::messages::emit(output, &summary)
}
