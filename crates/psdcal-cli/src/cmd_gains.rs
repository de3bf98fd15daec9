//! `psdcal gains`: relative channel gains from equal-current records.

use psdcal_io::write_gains;

use crate::cli::Output;
use crate::cli_gains::GainsArgs;

/// Runs `gains`.
pub fn run(args: &GainsArgs, output: Output) -> anyhow::Result<()> {
    let file = psdcal::estimate_gains(&args.signals, args.method.into())?;
    if let Some(path) = &args.out {
        write_gains(path, &file)?;
    }
    match (output, &args.out) {
        (Output::Quiet, _) => {}
        (Output::Json, _) | (_, None) => println!("{}", serde_json::to_string_pretty(&file)?),
        (Output::Text, Some(path)) => {
            println!(
                "gains relative to x1 from {} equal-current records ({}):",
                file.records,
                args.signals.display()
            );
            for (name, g, s) in [
                ("g_x2", file.x2, file.std.g_x2),
                ("g_y1", file.y1, file.std.g_y1),
                ("g_y2", file.y2, file.std.g_y2),
            ] {
                println!("  {name} = {g:.8} ± {s:.2e}");
            }
            println!("wrote {}", path.display());
        }
    }
    Ok(())
}
