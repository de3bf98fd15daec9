//! `psdcal gains`: relative channel gains from equal-current records.

use crate::cli::Output;
use crate::cli_gains::GainsArgs;

/// Runs `gains` (without `--out`, gains.json goes to standard output).
pub fn run(args: &GainsArgs, output: Output) -> anyhow::Result<()> {
    let file = psdcal::estimate_gains(&args.signals, args.method.into())?;
    match &args.out {
        Some(path) => psdcal_io::write_gains(path, &file)?,
        None if output != Output::Json => {
            println!("{}", serde_json::to_string_pretty(&file)?);
            return Ok(());
        }
        None => {}
    }
    let summary = psdcal::gains_summary(&file, &args.signals, args.out.as_deref())?;
    crate::report::emit(output, &summary)
}
