//! `psdcal calibrate`: read and validate a data set, calibrate, write
//! calibration.json (and the residuals), and summarise.

use std::fmt::Write as _;
use std::io::Write as _;

use anyhow::Context as _;
use psdcal_calib::{
    calibrate, CalibrateOptions, CalibrationData, CalibrationResult, CostKind, ImageObservations,
    InitOptions, NoiseModel, Observation, RefineOptions,
};
use psdcal_io::{
    validate_data_set, write_atomic, write_calibration, Calibration, Observations, Signals,
    Template, ValidatedDataSet, ValidationOptions,
};
use psdcal_model::{ChannelGains, Param, SensorModel};

use crate::cli::{CalibrateConfig, Output, PointSource};
use crate::report::print_warnings;

/// Runs `calibrate`.
pub fn run(config: &CalibrateConfig, output: Output) -> anyhow::Result<()> {
    let template = Template::read(&config.template)?;
    let known_gains = config
        .gains_file
        .as_ref()
        .map(psdcal_io::read_gains)
        .transpose()?;
    let start_gains = known_gains
        .as_ref()
        .map_or(ChannelGains::UNIT, |g| g.gains());
    let mut signals = None;
    let observations = match &config.points {
        PointSource::Observations(path) => Observations::read(path)?,
        PointSource::Signals(path) => {
            let s = Signals::read(path)?;
            let o = s.to_observations(&config.geometry, &start_gains)?;
            signals = Some(s);
            o
        }
    };
    let options = ValidationOptions {
        geometry: config.geometry,
        strict: config.strict,
    };
    let set = validate_data_set(&template, &observations, &options)?;
    print_warnings(&set.warnings);
    let mut data = calibration_data(&template, &set, config);
    if let (Some(signals), true) = (&signals, config.fit_gains) {
        // The amplitudes behind every validated point, for the gains.
        let by_key: std::collections::HashMap<(&str, &str), psdcal_model::Amplitudes> = signals
            .rows
            .iter()
            .map(|r| ((r.image.as_str(), r.led.as_str()), r.amplitudes()))
            .collect();
        let amplitudes: Option<Vec<Vec<psdcal_model::Amplitudes>>> = set
            .images
            .iter()
            .map(|im| {
                im.points
                    .iter()
                    .map(|(led, _)| {
                        by_key
                            .get(&(im.id.as_str(), template.leds[*led].id.as_str()))
                            .copied()
                    })
                    .collect()
            })
            .collect();
        data.amplitudes = amplitudes;
    }
    let result = calibrate(&data, &calibrate_options(config)).context("calibration failed")?;
    let mut file = calibration_file(&result, &data, config);
    if let Some(g) = &known_gains {
        file.gains = Some(psdcal_io::GainsRecord::new(&g.gains(), false));
    }
    write_calibration(&config.out, &file)?;
    if let Some(path) = &config.residuals {
        write_residuals(path, &template, &data, &result)?;
    }
    for warning in &result.warnings {
        eprintln!("warning: {warning}");
    }
    match output {
        Output::Quiet => {}
        Output::Json => println!("{}", serde_json::to_string_pretty(&result.summary())?),
        Output::Text => print!("{}", render(&result, config)),
    }
    Ok(())
}

/// The library's input from the validated files.
fn calibration_data(
    template: &Template,
    set: &ValidatedDataSet,
    config: &CalibrateConfig,
) -> CalibrationData {
    CalibrationData {
        amplitudes: None,
        template: template
            .leds
            .iter()
            .map(|l| nalgebra::Vector2::new(l.x_mm, l.y_mm))
            .collect(),
        lines: template
            .line_groups()
            .into_iter()
            .filter(|g| g.leds.len() >= 3)
            .map(|g| g.leds)
            .collect(),
        images: set
            .images
            .iter()
            .map(|image| ImageObservations {
                id: image.id.clone(),
                points: image
                    .points
                    .iter()
                    .map(|&(led, measured)| Observation { led, measured })
                    .collect(),
            })
            .collect(),
        geometry: config.geometry,
    }
}

fn calibrate_options(config: &CalibrateConfig) -> CalibrateOptions {
    let mut base = SensorModel::pinhole(config.focal_guess.unwrap_or(8.0), 0.0, 0.0);
    for &(p, value) in &config.fixed_values {
        base.set(p, value);
    }
    CalibrateOptions {
        init: InitOptions {
            preliminary: config.preliminary,
            normalize: config.normalize,
            focal_guess: config.focal_guess,
            ..InitOptions::default()
        },
        refine: RefineOptions {
            cost: config.cost,
            noise: config.noise,
            free: config.free.clone(),
            fit_gains: config.fit_gains,
            robust: config.robust,
            ..RefineOptions::default()
        },
        base: base.into(),
        ..CalibrateOptions::default()
    }
}

/// calibration.json from the result.
fn calibration_file(
    result: &CalibrationResult,
    data: &CalibrationData,
    config: &CalibrateConfig,
) -> Calibration {
    let mut file = Calibration::from_model(&result.sensor_model(), &config.geometry);
    let free: Vec<Param> = result.free.iter().filter_map(|n| n.parse().ok()).collect();
    file.set_estimated(&free);
    if let Some(g) = &result.gains {
        file.gains = Some(psdcal_io::GainsRecord::new(g, true));
    }
    let m = &result.covariance.matrix;
    file.std = psdcal_io::StdDevs(
        result
            .covariance
            .names
            .iter()
            .enumerate()
            .map(|(k, name)| (name.clone(), m[(k, k)].max(0.0).sqrt()))
            .collect(),
    );
    file.covariance = psdcal_io::Covariance {
        parameters: result.covariance.names.clone(),
        matrix: (0..m.nrows())
            .map(|i| {
                (0..m.ncols())
                    .map(|j| 0.5 * (m[(i, j)] + m[(j, i)]))
                    .collect()
            })
            .collect(),
    };
    let stats = &result.statistics;
    file.fit = psdcal_io::FitSummary {
        cost: match result.cost_kind {
            CostKind::Template => psdcal_io::CostKind::Template,
            CostKind::Image => psdcal_io::CostKind::Image,
        },
        noise: config.noise.name().to_string(),
        residual_mm2: stats.residual_mm2,
        rms_template_mm: stats.rms_template_mm,
        rms_image_mm: stats.rms_image_mm,
        iterations: result.refine.iterations,
        points: stats.points,
        images: stats.images,
        termination: format!("{:?}", result.refine.termination),
    };
    file.images = data
        .images
        .iter()
        .zip(&result.poses)
        .zip(&stats.per_image)
        .map(|((image, pose), s)| {
            psdcal_io::ImageFit::new(&image.id, pose, s.rms_template_mm, image.points.len())
        })
        .collect();
    file
}

/// Every point's residuals: template plane (mm) and sensor (mm).
fn write_residuals(
    path: &std::path::Path,
    template: &Template,
    data: &CalibrationData,
    result: &CalibrationResult,
) -> anyhow::Result<()> {
    write_atomic(path, |w| {
        writeln!(
            w,
            "image,led,x_mm,y_mm,X_mm,Y_mm,template_dx_mm,template_dy_mm,image_dx_mm,image_dy_mm"
        )?;
        for (image, pose) in data.images.iter().zip(&result.poses) {
            for obs in &image.points {
                let xy = data.template[obs.led];
                let t = result
                    .model
                    .back_project(pose, &obs.measured)
                    .map(|p| p - xy);
                let m = result.model.project(pose, &xy).map(|p| p - obs.measured);
                let fmt = |v: Option<f64>| v.map(|v| format!("{v:e}")).unwrap_or_default();
                writeln!(
                    w,
                    "{},{},{:e},{:e},{},{},{},{},{},{}",
                    csv_text(&image.id),
                    csv_text(&template.leds[obs.led].id),
                    obs.measured.x,
                    obs.measured.y,
                    xy.x,
                    xy.y,
                    fmt(t.as_ref().ok().map(|d| d.x)),
                    fmt(t.as_ref().ok().map(|d| d.y)),
                    fmt(m.as_ref().ok().map(|d| d.x)),
                    fmt(m.as_ref().ok().map(|d| d.y)),
                )?;
            }
        }
        Ok(())
    })?;
    Ok(())
}

/// A CSV field, quoted when it needs to be.
fn csv_text(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The human-readable summary.
fn render(result: &CalibrationResult, config: &CalibrateConfig) -> String {
    let mut out = String::new();
    let _ = write_summary(&mut out, result, config);
    out
}

fn write_summary(
    out: &mut String,
    r: &CalibrationResult,
    config: &CalibrateConfig,
) -> std::fmt::Result {
    let s = &r.statistics;
    let start = match r.init.route {
        psdcal_calib::InitRoute::ClosedForm => "closed form",
        psdcal_calib::InitRoute::FocalSearch => "focal-length search (closed form rejected)",
        psdcal_calib::InitRoute::FocalGuess => "focal-length search around --focal-guess",
    };
    writeln!(
        out,
        "calibrated {} images, {} points; start: {start}",
        s.images, s.points
    )?;
    if let Some(reason) = &r.init.closed_form_rejection {
        writeln!(out, "  closed form not used: {reason}")?;
    }
    writeln!(out)?;
    writeln!(out, "parameter          value           std    unit")?;
    let sensor = r.sensor_model();
    for p in Param::ALL {
        let value = sensor.get(p);
        match r.covariance.std(p.name()) {
            Some(sd) => writeln!(
                out,
                "{:<9} {:>15.8e} ± {:<11.3e} {}",
                p.name(),
                value,
                sd,
                p.unit()
            )?,
            None if value != 0.0 => writeln!(
                out,
                "{:<9} {:>15.8e}   (fixed)     {}",
                p.name(),
                value,
                p.unit()
            )?,
            None => {}
        }
    }
    if let (Some(g), Some(sd)) = (&r.gains, r.covariance.gain_std()) {
        for ((name, value), s) in psdcal_calib::GAIN_NAMES.iter().zip(g.to_array()).zip(sd) {
            writeln!(out, "{name:<9} {value:>15.8e} ± {s:<11.3e} (relative gain)")?;
        }
        if let Some(start) = &r.gain_start {
            writeln!(out, "gain start: {start}")?;
        }
    }
    writeln!(out)?;
    let corr = r.covariance.correlation();
    if r.free.len() > 1 {
        write!(out, "correlation")?;
        for name in &r.covariance.names {
            write!(out, " {name:>6}")?;
        }
        writeln!(out)?;
        for (i, name) in r.covariance.names.iter().enumerate() {
            write!(out, "{name:<11}")?;
            for j in 0..r.covariance.names.len() {
                if j <= i {
                    write!(out, " {:>+6.3}", corr[(i, j)])?;
                }
            }
            writeln!(out)?;
        }
        writeln!(out)?;
    }
    let cost = match r.cost_kind {
        CostKind::Template => "template plane",
        CostKind::Image => "image plane",
    };
    writeln!(
        out,
        "cost minimised:   {cost}{}{}",
        if r.robust.is_some() { " (robust)" } else { "" },
        match r.noise {
            NoiseModel::Uniform => String::new(),
            noise => format!(", weighted by the {} noise model", noise.name()),
        }
    )?;
    writeln!(
        out,
        "residual:         {:.6e} mm² (sum of squared template-plane errors)",
        s.residual_mm2
    )?;
    writeln!(
        out,
        "RMS error:        {:.4e} mm on the template, {:.4e} mm on the sensor",
        s.rms_template_mm, s.rms_image_mm
    )?;
    writeln!(
        out,
        "iterations:       {} ({:?})",
        r.refine.iterations, r.refine.termination
    )?;
    if let Some(g) = &r.global {
        writeln!(
            out,
            "l1 search:        {} minima found, {} refinements",
            g.minima.len(),
            g.refinements
        )?;
        for m in &g.minima {
            writeln!(
                out,
                "                  cost {:.6e} at l1 = {:.4e}, k1 = {:.4e}, f = {:.4}",
                m.cost, m.l1, m.k1, m.f
            )?;
        }
    }
    writeln!(out)?;
    writeln!(out, "image   points   RMS template (mm)   RMS sensor (mm)")?;
    for i in &s.per_image {
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
