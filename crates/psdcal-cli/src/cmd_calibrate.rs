//! `psdcal calibrate`: read and validate a data set, calibrate, write
//! calibration.json (and the residuals), and summarise.

use std::fmt::Write as _;

use psdcal::{calibrate, DataSet, DataSetFiles, FitReport, LoadOptions};

use crate::cli::{CalibrateConfig, Output};
use crate::report::print_warnings;

/// Runs `calibrate`.
pub fn run(config: &CalibrateConfig, output: Output) -> anyhow::Result<()> {
    let files = DataSetFiles {
        template: config.template.clone(),
        points: config.points.clone(),
        gains: config.gains_file.clone(),
    };
    let load = LoadOptions {
        geometry: config.geometry,
        strict: config.strict,
    };
    let set = DataSet::from_files(&files, &load)?;
    print_warnings(set.warnings());
    let mut calibrated = calibrate(&set, &config.options)?;
    let argv: Vec<String> = std::env::args().collect();
    calibrated.set_command(&argv.join(" "));
    calibrated.write(&set, &config.out, config.residuals.as_deref())?;
    for warning in &calibrated.report.warnings {
        eprintln!("warning: {warning}");
    }
    match output {
        Output::Quiet => {}
        Output::Json => println!("{}", calibrated.summary_json()?),
        Output::Text => print!("{}", render(&calibrated.report, config)),
    }
    Ok(())
}

/// The human-readable summary.
fn render(report: &FitReport, config: &CalibrateConfig) -> String {
    let mut out = String::new();
    let _ = write_summary(&mut out, report, config);
    out
}

fn write_summary(out: &mut String, r: &FitReport, config: &CalibrateConfig) -> std::fmt::Result {
    writeln!(
        out,
        "calibrated {} images, {} points; start: {}",
        r.images, r.points, r.start
    )?;
    if let Some(reason) = &r.closed_form_rejection {
        writeln!(out, "  closed form not used: {reason}")?;
    }
    writeln!(out)?;
    writeln!(out, "parameter          value           std    unit")?;
    for p in &r.parameters {
        match p.std {
            Some(sd) => writeln!(
                out,
                "{:<9} {:>15.8e} ± {:<11.3e} {}",
                p.name, p.value, sd, p.unit
            )?,
            None if p.value != 0.0 => writeln!(
                out,
                "{:<9} {:>15.8e}   (fixed)     {}",
                p.name, p.value, p.unit
            )?,
            None => {}
        }
    }
    if !r.gains.is_empty() {
        for (name, value, s) in &r.gains {
            writeln!(out, "{name:<9} {value:>15.8e} ± {s:<11.3e} (relative gain)")?;
        }
        if let Some(start) = &r.gain_start {
            writeln!(out, "gain start: {start}")?;
        }
    }
    writeln!(out)?;
    if !r.correlation_names.is_empty() {
        write!(out, "correlation")?;
        for name in &r.correlation_names {
            write!(out, " {name:>6}")?;
        }
        writeln!(out)?;
        for (i, name) in r.correlation_names.iter().enumerate() {
            write!(out, "{name:<11}")?;
            for value in r.correlation[i].iter().take(i + 1) {
                write!(out, " {value:>+6.3}")?;
            }
            writeln!(out)?;
        }
        writeln!(out)?;
    }
    writeln!(
        out,
        "cost minimised:   {}{}{}",
        r.cost,
        if r.robust { " (robust)" } else { "" },
        r.noise.map_or(String::new(), |n| format!(
            ", weighted by the {n} noise model"
        ))
    )?;
    writeln!(
        out,
        "residual:         {:.6e} mm² (sum of squared template-plane errors)",
        r.residual_mm2
    )?;
    writeln!(
        out,
        "RMS error:        {:.4e} mm on the template, {:.4e} mm on the sensor",
        r.rms_template_mm, r.rms_image_mm
    )?;
    writeln!(
        out,
        "iterations:       {} ({})",
        r.iterations, r.termination
    )?;
    if let Some(g) = &r.global {
        writeln!(
            out,
            "l1 search:        {} minima found, {} refinements",
            g.minima.len(),
            g.refinements
        )?;
        for [cost, l1, k1, f] in &g.minima {
            writeln!(
                out,
                "                  cost {cost:.6e} at l1 = {l1:.4e}, k1 = {k1:.4e}, f = {f:.4}"
            )?;
        }
    }
    writeln!(out)?;
    writeln!(out, "image   points   RMS template (mm)   RMS sensor (mm)")?;
    for i in &r.per_image {
        writeln!(
            out,
            "{:<7} {:>6}   {:>17.4e}   {:>15.4e}",
            i.id, i.points, i.rms_template_mm, i.rms_image_mm
        )?;
    }
    writeln!(out)?;
    writeln!(out, "wrote {}", config.out.display())?;
    if let Some(path) = &config.residuals {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}
