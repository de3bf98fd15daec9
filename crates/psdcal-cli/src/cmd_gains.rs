//! `psdcal gains`: relative channel gains from equal-current records.

use psdcal_calib::equal_current_gains;
use psdcal_io::{write_gains, GainStd, GainsFile, PointInput, Points, GAINS_FORMAT};

use crate::cli::Output;
use crate::cli_gains::GainsArgs;

/// Runs `gains`.
pub fn run(args: &GainsArgs, output: Output) -> anyhow::Result<()> {
    let points = Points::read(&args.signals)?;
    let records: Vec<_> = points
        .rows
        .iter()
        .filter_map(|r| match r.input {
            PointInput::Amplitudes(a) => Some(a),
            PointInput::Position(_) => None,
        })
        .collect();
    if records.is_empty() {
        anyhow::bail!(
            "{}: no amplitude columns (vx1, vx2, vy1, vy2); the equal-current method needs electrode amplitudes",
            args.signals.display()
        );
    }
    let estimate = equal_current_gains(&records)?;
    let file = GainsFile {
        format: GAINS_FORMAT.into(),
        version: 1,
        method: args.method.clone(),
        x2: estimate.gains.x2,
        y1: estimate.gains.y1,
        y2: estimate.gains.y2,
        std: GainStd {
            g_x2: estimate.std[0],
            g_y1: estimate.std[1],
            g_y2: estimate.std[2],
        },
        records: estimate.records,
    };
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
