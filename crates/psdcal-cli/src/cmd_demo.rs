//! `psdcal demo`: the main job on built-in data (the library's `demo`),
//! printed.

use crate::cli::Output;
use crate::cli_sim::DemoArgs;

/// Runs `demo`.
pub fn run(args: &DemoArgs, output: Output) -> anyhow::Result<()> {
    let d = psdcal::demo(args.seed)?;
    match output {
        Output::Quiet => {}
        Output::Json => println!(
            "{}",
            serde_json::json!({
                "seed": d.seed,
                "lens": 2,
                "snr_db": 40.0,
                "images": d.images,
                "points": d.points,
                "parameters": d.parameters.iter().map(|p| serde_json::json!({
                    "name": p.param.name(), "truth": p.truth, "estimate": p.estimate, "std": p.std,
                })).collect::<Vec<_>>(),
                "residual_mm2": d.residual_mm2,
                "rms_image_mm": d.rms_image_mm,
                "iterations": d.iterations,
                "aoa_rms_error_deg": d.aoa_rms_error_deg,
                "elapsed_s": d.elapsed_s,
            })
        ),
        Output::Text => {
            println!(
                "psdcal demo: the paper's lens 2 (f = 8 mm, k1 = 1e-2, k2 = 3e-5, centre (0.5, -0.7) mm),\n\
                 40 dB SNR per channel through the simulated signal chain, {} template poses\n\
                 of the 14-LED template ({} points), seed {}; calibrated from automatic initialisation.\n",
                d.images, d.points, d.seed
            );
            println!("parameter         truth        estimate           std    error/std");
            for p in &d.parameters {
                let z = p
                    .std
                    .filter(|s| *s > 0.0)
                    .map_or("".into(), |s| format!("{:+.2}", (p.estimate - p.truth) / s));
                println!(
                    "{:<6} {:>15.6e} {:>15.6e} {:>13.3e} {:>12}",
                    p.param.name(),
                    p.truth,
                    p.estimate,
                    p.std.unwrap_or(0.0),
                    z
                );
            }
            println!();
            println!(
                "residual {:.4e} mm², RMS {:.3e} mm on the sensor, {} iterations",
                d.residual_mm2, d.rms_image_mm, d.iterations
            );
            println!(
                "angle-of-arrival error over held-out directions: {:.4}° RMS ({:.1} mm at 5 m)",
                d.aoa_rms_error_deg,
                5000.0 * d.aoa_rms_error_deg.to_radians()
            );
            println!("done in {:.2} s. Next: psdcal simulate --out sim, psdcal calibrate, psdcal study all", d.elapsed_s);
        }
    }
    Ok(())
}
