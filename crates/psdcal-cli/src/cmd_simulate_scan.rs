//! `psdcal simulate-scan`: a simulated lensless raster scan of the PSD
//! (arguments and printing; the work is `psdcal::simulate_scan_file`).

use std::path::PathBuf;

use clap::Args;
use psdcal::{PsdGeometry, ScanRequest};

use crate::messages::Output;
use psdcal::option_text::side_mm;

/// Simulate a lensless raster scan of the PSD (scan.csv for psd-map)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct SimulateScanArgs {
    /// Raster step, mm (0.25 on a 9 mm PSD: 37 × 37 positions)
    #[arg(long, value_name = "MM", default_value = "0.25")]
    pub step: f64,
    /// Stage positioning error per axis (σ), µm
    #[arg(long, value_name = "UM", default_value = "0.3")]
    pub stage_sigma: f64,
    /// Per-channel SNR in dB (no noise when absent)
    #[arg(long, value_name = "DB", allow_negative_numbers = true)]
    pub snr: Option<f64>,
    /// An ideal PSD, without the simulated non-linearity
    #[arg(long)]
    pub linear: bool,
    /// Active area side along x, mm
    #[arg(long, value_name = "MM", default_value = "9", value_parser = side_mm)]
    pub lx: f64,
    /// Active area side along y, mm
    #[arg(long, value_name = "MM", default_value = "9", value_parser = side_mm)]
    pub ly: f64,
    /// Seed of every random draw
    #[arg(long, value_name = "S", default_value = "1")]
    pub seed: u64,
    /// Where to write scan.csv (atomically)
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// Runs `simulate-scan`.
pub fn run(args: &SimulateScanArgs, output: Output) -> anyhow::Result<()> {
    let scan = psdcal::simulate_scan_file(&ScanRequest {
        step_mm: args.step,
        stage_sigma_um: args.stage_sigma,
        snr_db: args.snr,
        nonlinearity: !args.linear,
        geometry: PsdGeometry {
            lx: args.lx,
            ly: args.ly,
        },
        seed: args.seed,
        out: args.out.clone(),
    })?;
    crate::messages::emit(output, &scan.summary(&args.out))
}
