//! `psdcal report`: a self-contained HTML page of a calibration with its
//! plots (the library's `write_report`, drawn by psdcal-report).

use psdcal::ReportRequest;

use crate::cli::Output;
use crate::cli_report::ReportConfig;
use crate::report::print_warnings;

/// Runs `report`.
pub fn run(config: &ReportConfig, output: Output) -> anyhow::Result<()> {
    let written = psdcal::write_report(&ReportRequest {
        calibration: config.calibration.clone(),
        data: config.data.clone(),
        out: config.out.clone(),
    })?;
    print_warnings(&written.warnings);
    match output {
        Output::Quiet => {}
        Output::Json => {
            let json = serde_json::json!({
                "report": written.html.display().to_string(),
                "plots": written.plots,
                "files": written.files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
            });
            println!("{}", serde_json::to_string_pretty(&json)?);
        }
        Output::Text => println!(
            "wrote {} and {} plots (SVG and PNG) into {}",
            written.html.display(),
            written.plots.len(),
            config.out.display()
        ),
    }
    Ok(())
}
