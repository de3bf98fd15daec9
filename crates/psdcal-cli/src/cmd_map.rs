//! `psdcal map`: AoA and position error maps over the sensor area (the
//! paper's Figure 9; the library's `map_table`).

use psdcal::MapRequest;

use crate::cli::Output;
use crate::cli_locate::MapConfig;
use crate::report::print_row_warnings;

/// Runs `map`.
pub fn run(config: &MapConfig, output: Output) -> anyhow::Result<()> {
    let map = psdcal::map_table(&MapRequest {
        model: config.model.clone(),
        source: config.source.clone(),
        distance_mm: config.distance_mm,
        grid: config.grid,
        paper: config.paper,
    })?;
    map.table.write_to(config.out.as_deref())?;
    print_row_warnings(&map.count);
    match (output, &config.out) {
        (Output::Quiet, _) => {}
        (Output::Json, out) => {
            let json = serde_json::json!({
                "command": "map",
                "model": map.model_name,
                "errors": map.source_text,
                "grid": config.grid,
                "distance_mm": config.distance_mm,
                "out": out.as_ref().map(|p| p.display().to_string()),
                "max_aoa_error_deg": map.max_aoa_deg,
                "max_position_error_mm": map.max_position_mm,
                "rows": map.count.to_json(),
            });
            println!("{}", serde_json::to_string_pretty(&json)?);
        }
        (Output::Text, out) => {
            let text = format!(
                "map: {}, {}, {n} x {n} grid over {lx} x {ly} mm, plane at {s} mm: largest AoA \
                 error {aoa}°, largest position error {pos} mm; {counts}",
                map.model_name,
                map.source_text,
                n = config.grid,
                lx = map.geometry.lx,
                ly = map.geometry.ly,
                s = config.distance_mm,
                aoa = map.max_aoa_deg.map_or("-".into(), |v| format!("{v:.4}")),
                pos = map.max_position_mm.map_or("-".into(), |v| if v < 1e6 {
                    format!("{v:.2}")
                } else {
                    format!("{v:.3e}")
                }),
                counts = map.count.summary(),
            );
            match out {
                Some(path) => println!("{text}; wrote {}", path.display()),
                None => eprintln!("{text}"),
            }
        }
    }
    Ok(())
}
