//! `psdcal report`: a self-contained HTML page of a calibration with its
//! plots (psdcal-report), and each plot as SVG and PNG.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context as _};
use nalgebra::Vector2;
use psdcal_io::{
    read_calibration, validate_data_set, write_atomic_bytes, Calibration, Observations, Template,
    ValidationOptions,
};
use psdcal_locate::{error_map, ErrorSource, MapOptions};
use psdcal_model::{Param, SensorModel};
use psdcal_report::{
    aoa_sensitivity_svg, coverage_png, coverage_svg, distortion_field_png, distortion_field_svg,
    heat_map_png, heat_map_svg, line_plot_png, paper_sensitivity_curves, residuals_png,
    residuals_svg, spiral_png, spiral_svg, Arrow, ArrowSet, Block, Frame, HeatCell, Page, PointSet,
    ReportError, Table,
};

use crate::cli::Output;
use crate::cli_report::ReportConfig;
use crate::locate_output::calibrated_sensor;

/// Grid points per side of the error maps.
const MAP_GRID: usize = 21;
/// Standard deviations of the error maps.
const MAP_K: f64 = 2.0;

/// Writes a plot's PNG file.
type WritePng = Box<dyn Fn(&Path) -> Result<(), ReportError>>;

/// Points on the sensor, mm.
type Points = Vec<(f64, f64)>;

/// One plot: its file stem, SVG, caption and how to write its PNG.
struct Plot {
    name: &'static str,
    svg: String,
    caption: String,
    png: WritePng,
}

/// Runs `report`.
pub fn run(config: &ReportConfig, output: Output) -> anyhow::Result<()> {
    let calibration = read_calibration(&config.calibration)?;
    let model = calibration.to_model();
    let geometry = calibration.geometry();
    let data = match &config.data {
        Some((t, o)) => {
            let template = Template::read(t)?;
            let observations = Observations::read(o)?;
            let set = validate_data_set(
                &template,
                &observations,
                &ValidationOptions {
                    geometry,
                    strict: false,
                },
            )?;
            crate::report::print_warnings(&set.warnings);
            Some((template, set))
        }
        None => None,
    };
    std::fs::create_dir_all(&config.out)
        .with_context(|| format!("cannot create the output folder {}", config.out.display()))?;

    let (lx, ly) = (geometry.lx, geometry.ly);
    let mut plots: Vec<Plot> = Vec::new();
    let mut image_rows: Vec<Vec<String>> = Vec::new();
    if let Some((template, set)) = &data {
        let mut coverage = Vec::new();
        let mut on_template = Vec::new();
        let mut on_sensor = Vec::new();
        for image in &set.images {
            let pose = calibration
                .images
                .iter()
                .find(|i| i.id == image.id)
                .map(|i| i.pose());
            coverage.push(PointSet {
                label: image.id.clone(),
                points: image.points.iter().map(|(_, m)| (m.x, m.y)).collect(),
            });
            let Some(pose) = pose else {
                image_rows.push(vec![
                    image.id.clone(),
                    image.points.len().to_string(),
                    "not in the calibration".into(),
                    "–".into(),
                ]);
                continue;
            };
            let (mut t_arrows, mut s_arrows) = (Vec::new(), Vec::new());
            let (mut t_sq, mut s_sq) = (0.0, 0.0);
            for (led, m) in &image.points {
                let l = &template.leds[*led];
                let xy = Vector2::new(l.x_mm, l.y_mm);
                if let Ok(b) = model.back_project(&pose, m) {
                    let e = b - xy;
                    t_sq += e.norm_squared();
                    t_arrows.push(Arrow {
                        at: (xy.x, xy.y),
                        delta: (e.x, e.y),
                    });
                }
                if let Ok(p) = model.project(&pose, &xy) {
                    let e = p - m;
                    s_sq += e.norm_squared();
                    s_arrows.push(Arrow {
                        at: (m.x, m.y),
                        delta: (e.x, e.y),
                    });
                }
            }
            let rms = |sq: f64, n: usize| {
                if n == 0 {
                    "–".to_string()
                } else {
                    format!("{:.4}", (sq / n as f64).sqrt())
                }
            };
            image_rows.push(vec![
                image.id.clone(),
                image.points.len().to_string(),
                rms(t_sq, t_arrows.len()),
                rms(s_sq, s_arrows.len()),
            ]);
            on_template.push(ArrowSet {
                label: image.id.clone(),
                arrows: t_arrows,
            });
            on_sensor.push(ArrowSet {
                label: image.id.clone(),
                arrows: s_arrows,
            });
        }
        let frame = Frame::sensor("Coverage of the sensor by the images", lx, ly);
        let svg = coverage_svg(&coverage, lx, ly, &frame)?;
        let points = set.total_points();
        plots.push(Plot {
            name: "coverage",
            svg,
            caption: format!(
                "{points} measured points of {} images on the {lx} × {ly} mm active area (paper Figure 8)",
                set.images.len()
            ),
            png: Box::new(move |p| coverage_png(&coverage, lx, ly, &frame, p)),
        });
        let leds = template.leds.iter().map(|l| (l.x_mm, l.y_mm));
        for (name, sets, frame0, what) in [
            (
                "residuals_template",
                on_template,
                Frame::fit("Template-plane residuals", "X (mm)", "Y (mm)", leds),
                "template plane (back-projected point − LED)",
            ),
            (
                "residuals_sensor",
                on_sensor,
                Frame::sensor("Sensor residuals", lx, ly),
                "sensor (projected LED − measured point)",
            ),
        ] {
            let span =
                (frame0.x_range.1 - frame0.x_range.0).max(frame0.y_range.1 - frame0.y_range.0);
            let scale = arrow_scale(sets.iter().flat_map(|s| &s.arrows), span);
            let mut frame = frame0;
            frame.title = format!("{} × {}", frame.title, round_scale(scale));
            let svg = residuals_svg(&sets, scale, &frame)?;
            plots.push(Plot {
                name,
                svg,
                caption: format!(
                    "Residual vectors per image on the {what}, arrows scaled × {} (paper Figure 13)",
                    round_scale(scale)
                ),
                png: Box::new(move |p| residuals_png(&sets, scale, &frame, p)),
            });
        }
    }

    // The distortion field: measured grid points → ideal points.
    let n = 11;
    let field: Vec<Arrow> = (0..n * n)
        .map(|k| {
            let m = Vector2::new(
                lx * (-0.45 + 0.9 * (k % n) as f64 / (n - 1) as f64),
                ly * (-0.45 + 0.9 * (k / n) as f64 / (n - 1) as f64),
            );
            let i = model.undistort(&m);
            Arrow {
                at: (m.x, m.y),
                delta: (i.x - m.x, i.y - m.y),
            }
        })
        .collect();
    let scale = arrow_scale(field.iter(), lx.max(ly) * 1.1);
    let frame = Frame::sensor(
        &format!("Distortion correction × {}", round_scale(scale)),
        lx,
        ly,
    );
    let svg = distortion_field_svg(&field, scale, &frame)?;
    plots.push(Plot {
        name: "distortion_field",
        svg,
        caption: format!(
            "Correction of the calibrated model, measured → ideal point, arrows scaled × {} (paper Figure 16)",
            round_scale(scale)
        ),
        png: Box::new(move |p| distortion_field_png(&field, scale, &frame, p)),
    });
    let (measured, corrected) = spiral(&model, 0.45 * lx.min(ly));
    let frame = Frame::fit(
        "A measured spiral and its correction",
        "x (mm)",
        "y (mm)",
        measured.iter().chain(&corrected).copied(),
    );
    let svg = spiral_svg(&measured, &corrected, &frame)?;
    plots.push(Plot {
        name: "spiral",
        svg,
        caption: "A spiral of measured points and the same points corrected by the model (paper Figure 16)".into(),
        png: Box::new(move |p| spiral_png(&measured, &corrected, &frame, p)),
    });
    let f = model.intrinsics.f;
    let svg = aoa_sensitivity_svg(f, 0.5 * lx)?;
    plots.push(Plot {
        name: "aoa_sensitivity",
        svg,
        caption: format!(
            "Change of the angle of arrival per mm of error in x and in f, f = {f:.3} mm (paper Figure 6, P40–P41)"
        ),
        png: Box::new(move |p| {
            let curves = paper_sensitivity_curves(f, 0.5 * lx, 101);
            let frame = Frame::fit(
                "AoA sensitivity to Δx and Δf (P40–P41)",
                "x (mm)",
                "deg per mm",
                curves.iter().flat_map(|c| c.points.iter().copied()).chain([(0.0, 0.0)]),
            );
            line_plot_png(&curves, &frame, p)
        }),
    });
    let sensor = calibrated_sensor(&calibration, &config.calibration)?;
    if !sensor.covariance.is_empty() {
        let map = error_map(
            &model,
            &geometry,
            &ErrorSource::Covariance {
                covariance: sensor.covariance.clone(),
                k: MAP_K,
            },
            &MapOptions {
                grid: MAP_GRID,
                ..MapOptions::default()
            },
        )?;
        let step = (lx / (MAP_GRID - 1) as f64, ly / (MAP_GRID - 1) as f64);
        for (name, title, label, position) in [
            ("aoa_error_map", "AoA error, 2σ", "AoA error (deg)", false),
            (
                "position_error_map",
                "Position error at 5 m, 2σ",
                "position error (mm)",
                true,
            ),
        ] {
            let cells: Vec<HeatCell> = map
                .cells
                .iter()
                .filter_map(|c| {
                    let v = c.values.as_ref().ok()?;
                    Some(HeatCell {
                        x: c.measured.x,
                        y: c.measured.y,
                        value: if position {
                            v.position_error_total
                        } else {
                            v.aoa_error_total.to_degrees()
                        },
                    })
                })
                .collect();
            if cells.is_empty() {
                continue;
            }
            let max = cells.iter().map(|c| c.value).fold(0.0, f64::max);
            let frame = Frame::sensor(title, lx, ly);
            let svg = heat_map_svg(&cells, step, &frame, label)?;
            plots.push(Plot {
                name,
                svg,
                caption: format!(
                    "{title} from the calibration's covariance over the active area, largest {max:.4} {} (paper Figure 9)",
                    if position { "mm" } else { "deg" }
                ),
                png: Box::new(move |p| heat_map_png(&cells, step, &frame, label, p)),
            });
        }
    }

    let page = build_page(config, &calibration, &model, &image_rows, &plots);
    let html_path = config.out.join("report.html");
    write_atomic_bytes(&html_path, page.render().as_bytes())?;
    let mut files: Vec<PathBuf> = vec![html_path.clone()];
    for plot in &plots {
        let svg_path = config.out.join(format!("{}.svg", plot.name));
        write_atomic_bytes(&svg_path, plot.svg.as_bytes())?;
        let png_path = config.out.join(format!("{}.png", plot.name));
        let tmp = config.out.join(format!(".{}.tmp.png", plot.name));
        (plot.png)(&tmp)?;
        std::fs::rename(&tmp, &png_path)
            .map_err(|e| anyhow!("cannot write {}: {e}", png_path.display()))?;
        files.push(svg_path);
        files.push(png_path);
    }
    match output {
        Output::Quiet => {}
        Output::Json => {
            let json = serde_json::json!({
                "report": html_path.display().to_string(),
                "plots": plots.iter().map(|p| p.name).collect::<Vec<_>>(),
                "files": files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
            });
            println!("{}", serde_json::to_string_pretty(&json)?);
        }
        Output::Text => println!(
            "wrote {} and {} plots (SVG and PNG) into {}",
            html_path.display(),
            plots.len(),
            config.out.display()
        ),
    }
    Ok(())
}

/// A scale that makes the longest arrow 8 % of `span`.
fn arrow_scale<'a>(arrows: impl Iterator<Item = &'a Arrow>, span: f64) -> f64 {
    let longest = arrows
        .map(|a| a.delta.0.hypot(a.delta.1))
        .filter(|l| l.is_finite())
        .fold(0.0, f64::max);
    if longest > 0.0 {
        let s = 0.08 * span / longest;
        // One significant digit, so the caption's factor is the exact one.
        let p = 10f64.powf(s.log10().floor());
        (s / p).floor().max(1.0) * p
    } else {
        1.0
    }
}

fn round_scale(scale: f64) -> String {
    if scale >= 1.0 {
        format!("{scale:.0}")
    } else {
        format!("{scale}")
    }
}

/// A spiral of measured points of radius up to `radius` and its correction.
fn spiral(model: &SensorModel, radius: f64) -> (Points, Points) {
    let n = 120;
    let turns = 4.0;
    (0..n)
        .map(|k| {
            let u = k as f64 / (n - 1) as f64;
            let t = u * turns * std::f64::consts::TAU;
            let m = Vector2::new(radius * u * t.cos(), radius * u * t.sin());
            let i = model.undistort(&m);
            ((m.x, m.y), (i.x, i.y))
        })
        .unzip()
}

fn build_page(
    config: &ReportConfig,
    calibration: &Calibration,
    model: &SensorModel,
    image_rows: &[Vec<String>],
    plots: &[Plot],
) -> Page {
    let file_name = |p: &Path| p.display().to_string();
    let short = config.calibration.file_name().map_or_else(
        || file_name(&config.calibration),
        |n| n.to_string_lossy().into_owned(),
    );
    let mut page = Page::new(&format!("psdcal calibration report: {short}"));
    let mut sources = vec![format!("calibration: {}", file_name(&config.calibration))];
    if let Some((t, o)) = &config.data {
        sources.push(format!("template: {}", file_name(t)));
        sources.push(format!("observations: {}", file_name(o)));
    }
    sources.push(format!(
        "written by {} {}; sensor {} × {} mm",
        calibration.software.name,
        calibration.software.version,
        calibration.sensor.lx_mm,
        calibration.sensor.ly_mm
    ));
    page.push(Block::List(sources));
    page.push(Block::Heading("Parameters".into()));
    let rows = Param::ALL
        .iter()
        .map(|p| {
            let name = p.name();
            let estimated = calibration.estimated.contains(p);
            let sigma = calibration.std.get(name);
            vec![
                name.to_string(),
                format!("{:.6e}", model.get(*p)),
                sigma.map_or("–".into(), |s| format!("{s:.3e}")),
                p.unit().to_string(),
                if estimated { "estimated" } else { "fixed" }.to_string(),
            ]
        })
        .collect();
    page.push(Block::Table(Table {
        caption: "Model parameters ± one standard deviation".into(),
        headers: ["parameter", "value", "σ", "unit", ""]
            .map(String::from)
            .to_vec(),
        rows,
    }));
    let fit = &calibration.fit;
    page.push(Block::Table(Table {
        caption: "Fit summary".into(),
        headers: vec!["".into(), "value".into()],
        rows: vec![
            vec!["cost".into(), format!("{:?}", fit.cost)],
            vec!["residual (mm²)".into(), format!("{:.6e}", fit.residual_mm2)],
            vec![
                "RMS template-plane error (mm)".into(),
                format!("{:.4e}", fit.rms_template_mm),
            ],
            vec![
                "RMS image error (mm)".into(),
                format!("{:.4e}", fit.rms_image_mm),
            ],
            vec!["iterations".into(), fit.iterations.to_string()],
            vec!["points".into(), fit.points.to_string()],
            vec!["images".into(), fit.images.to_string()],
            vec!["termination".into(), fit.termination.clone()],
        ],
    }));
    page.push(Block::Heading("Plots".into()));
    page.push(Block::Figures(
        plots
            .iter()
            .map(|p| (p.svg.clone(), p.caption.clone()))
            .collect(),
    ));
    page.push(Block::Heading("Images".into()));
    page.push(Block::Table(Table {
        caption: "Per image: fitted pose and RMS error".into(),
        headers: ["image", "points", "RMS (mm)", "t (mm)", "rvec (rad)"]
            .map(String::from)
            .to_vec(),
        rows: calibration
            .images
            .iter()
            .map(|i| {
                vec![
                    i.id.clone(),
                    i.points.to_string(),
                    format!("{:.4e}", i.rms_mm),
                    format!("{:.2}, {:.2}, {:.2}", i.t_mm[0], i.t_mm[1], i.t_mm[2]),
                    format!("{:.4}, {:.4}, {:.4}", i.rvec[0], i.rvec[1], i.rvec[2]),
                ]
            })
            .collect(),
    }));
    if !image_rows.is_empty() {
        page.push(Block::Table(Table {
            caption: "Per image: residuals recomputed from the data".into(),
            headers: [
                "image",
                "points",
                "RMS template plane (mm)",
                "RMS sensor (mm)",
            ]
            .map(String::from)
            .to_vec(),
            rows: image_rows.to_vec(),
        }));
    }
    page
}
