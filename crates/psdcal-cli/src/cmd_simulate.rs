//! `psdcal simulate`: one simulated data set written as psdcal's input files
//! plus truth.json (the library's `simulate_files`).

use anyhow::Result;
use psdcal::{ReadLimits, SimulateRequest};

use crate::cli_sim::SimulateArgs;
use crate::messages::Output;

/// Runs `simulate`.
pub fn run(args: &SimulateArgs, output: Output, limits: ReadLimits, force: bool) -> Result<()> {
    let request = SimulateRequest {
        lens: args.lens,
        snr_db: args.snr,
        imbalance: args.imbalance,
        psd_distortion: args.psd_distortion,
        psd_nonlinearity: args.psd_nonlinearity,
        images: args.images,
        template: args.template,
        record_cycles: args.record_cycles,
        seed: args.seed,
        out: args.out.clone(),
        force,
    };
    let (written, files) = match (args.raw, &args.poses) {
        (None, Some(poses)) => (
            psdcal::simulate_files_at_poses(&request, poses, limits)?,
            Vec::new(),
        ),
        (None, None) => (psdcal::simulate_files(&request)?, Vec::new()),
        (Some(format), _) => psdcal::simulate_raw_files(
            &request,
            &psdcal::RawRequest {
                format,
                fdma: args.fdma,
                impairments: psdcal::Impairments::only(
                    &args
                        .impairments
                        .iter()
                        .flatten()
                        .copied()
                        .collect::<Vec<_>>(),
                ),
            },
        )?,
    };
    crate::messages::emit(output, &written.summary(&args.out, &files))
}
