//! `psdcal locate`: emitter positions with their 3-D covariance, on a plane
//! in the sensor frame or from a rig of sensors (the library's
//! `locate_table`).

use psdcal::LocateTarget;

use crate::cli::Output;
use crate::cli_locate::LocateConfig;
use crate::report::print_row_warnings;

/// Runs `locate`.
pub fn run(config: &LocateConfig, output: Output) -> anyhow::Result<()> {
    let answer = psdcal::locate_table(
        &config.target,
        &config.points,
        &config.options,
        config.out.as_deref(),
    )?;
    for w in &answer.warnings {
        eprintln!("warning: {w}");
    }
    print_row_warnings(&answer.count);
    let summary = format!(
        "locate: {} {}: {}",
        answer.rows,
        answer.what,
        answer.count.summary()
    );
    match (output, &config.out) {
        (Output::Quiet, _) => {}
        (Output::Json, out) => {
            let target = match &config.target {
                LocateTarget::Plane { calibration, plane } => serde_json::json!({
                    "calibration": calibration.display().to_string(),
                    "plane_normal": plane.normal().as_slice(),
                    "plane_offset_mm": plane.offset_mm(),
                    "frame": "sensor",
                }),
                LocateTarget::Rig(rig) => serde_json::json!({
                    "rig": rig.display().to_string(),
                    "frame": "world",
                    "weighted": config.options.weight_rays,
                }),
            };
            let json = serde_json::json!({
                "command": "locate",
                "points": config.points.display().to_string(),
                "target": target,
                "out": out.as_ref().map(|p| p.display().to_string()),
                "point_sigma_mm": config.point_sigma_given.then_some(config.options.point_sigma_mm),
                "rows": answer.count.to_json(),
            });
            println!("{}", serde_json::to_string_pretty(&json)?);
        }
        (Output::Text, Some(out)) => println!("{summary}; wrote {}", out.display()),
        (Output::Text, None) => eprintln!("{summary}"),
    }
    Ok(())
}
