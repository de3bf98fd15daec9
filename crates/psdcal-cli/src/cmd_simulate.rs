//! `psdcal simulate`: one simulated data set written as psdcal's input files
//! plus truth.json (the library's `simulate_files`).

use psdcal::SimulateRequest;

use crate::cli::Output;
use crate::cli_sim::SimulateArgs;

/// Runs `simulate`.
pub fn run(args: &SimulateArgs, output: Output) -> anyhow::Result<()> {
    let written = psdcal::simulate_files(&SimulateRequest {
        lens: args.lens.into(),
        snr_db: args.snr,
        imbalance: args.imbalance,
        psd_distortion: args.psd_distortion,
        psd_nonlinearity: args.psd_nonlinearity,
        images: args.images,
        template: args.template.into(),
        record_cycles: args.record_cycles,
        seed: args.seed,
        out: args.out.clone(),
    })?;
    match output {
        Output::Quiet => {}
        Output::Json => println!(
            "{}",
            serde_json::json!({
                "out": args.out.display().to_string(),
                "images": written.images,
                "points": written.points,
                "files": ["template.csv", "observations.csv", "signals.csv", "truth.json"],
            })
        ),
        Output::Text => {
            println!("{}", written.description);
            println!(
                "wrote {0}/template.csv, {0}/observations.csv, {0}/signals.csv, {0}/truth.json ({1} images, {2} points)",
                args.out.display(),
                written.images,
                written.points
            );
        }
    }
    Ok(())
}
