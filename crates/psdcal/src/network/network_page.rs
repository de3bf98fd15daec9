//! The report page of `calibrate-network --report DIR` (`DIR/index.html`,
//! one self-contained page, plots inline as SVG): the sensors and the wand's
//! path seen from above and from the side (each sensor a dot with its field
//! of view drawn as dotted edge rays 1.5 m long), each sensor's coverage of
//! its active area, the wand-length residuals per frame, the table of
//! sensors and the diagnostics.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use psdcal_network::Led;
use psdcal_report::{
    coverage_svg, histogram_svg, scatter_svg, Block, Frame, Page, PointSet, Table,
};

use crate::base::error::{Error, Result};
use crate::network::calibrate_network::NetworkCalibrated;
use crate::network::network_outputs::{claim_page, PAGE};

/// Length of the drawn field-of-view edges, mm.
const FOV_MM: f64 = 1500.0;

/// A sensor's dot and field-of-view edges, in the world.
fn sensor_points(c: &NetworkCalibrated, k: usize) -> Vec<Vector3<f64>> {
    let e = &c.result.sensors[k];
    let g = c.input.data.sensors[k].geometry;
    let world_from_sensor = e.sensor_from_world.inverse();
    let mut points = vec![e.position_mm];
    for (x, y) in [
        (-1.0, -1.0),
        (1.0, -1.0),
        (1.0, 1.0),
        (-1.0, 1.0),
        (0.0, 0.0),
    ] {
        let ab = e
            .model
            .ray(&nalgebra::Vector2::new(0.5 * x * g.lx, 0.5 * y * g.ly));
        let d = Vector3::new(ab.x, ab.y, 1.0).normalize();
        for s in 1..=15 {
            points.push(world_from_sensor.transform(&(d * (FOV_MM * s as f64 / 15.0))));
        }
    }
    points
}

/// One projected view (`axes` picks the world coordinates drawn).
fn view(
    c: &NetworkCalibrated,
    title: &str,
    axes: (usize, usize),
    labels: (&str, &str),
) -> Result<String> {
    let pick = |p: &Vector3<f64>| (p[axes.0], p[axes.1]);
    let mut sets = vec![PointSet {
        label: "wand (every 10th frame)".into(),
        points: c
            .result
            .wands
            .iter()
            .flatten()
            .step_by(10)
            .map(|w| pick(&w.t))
            .collect(),
    }];
    for k in 0..c.result.sensors.len() {
        sets.push(PointSet {
            label: c.input.data.sensors[k].id.clone(),
            points: sensor_points(c, k).iter().map(pick).collect(),
        });
    }
    let frame = Frame::fit(
        title,
        labels.0,
        labels.1,
        sets.iter().flat_map(|s| s.points.clone()),
    );
    Ok(scatter_svg(&sets, &frame)?)
}

/// Writes `dir/index.html` (module documentation); a page there that
/// psdcal did not write is kept, the run refused (unless `c.force`).
pub fn network_page(c: &NetworkCalibrated, dir: &Path) -> Result<PathBuf> {
    let folder = claim_page(dir, c.force)?;
    let r = &c.result;
    let d = &c.input.data;
    let mut page = Page::new("psdcal network calibration");
    page.push(Block::Paragraph(format!(
        "{} sensors, {} frames used of {} ({} dropped), point noise σ {:.3e} mm, wand-length RMS \
         {:.3} mm. {}.",
        d.sensors.len(),
        r.frames_used,
        d.frames.len(),
        r.dropped.len(),
        r.sigma_mm,
        r.diagnostics.wand_length_rms_mm,
        r.gauge.describe(&d.sensors[0].id)
    )));
    page.push(Block::Heading("Sensors and the wand's path".into()));
    page.push(Block::Figures(vec![
        (view(c, "from above", (0, 1), ("x (mm)", "y (mm)"))?, "Top view: sensors with their fields of view (dotted edges, 1.5 m) and the wand's centre.".into()),
        (view(c, "from the side", (0, 2), ("x (mm)", "z (mm)"))?, "Side view (x, z).".into()),
    ]));
    let mut table = Table {
        caption: "Sensors (position and σ in the world, mm; orientation σ in degrees)".into(),
        headers: [
            "sensor",
            "x",
            "y",
            "z",
            "σx",
            "σy",
            "σz",
            "σ rot (°)",
            "f (mm)",
            "points",
            "coverage",
            "RMS (mm)",
        ]
        .map(String::from)
        .to_vec(),
        rows: vec![],
    };
    for (k, e) in r.sensors.iter().enumerate() {
        let (sd, rot) = (e.position_sigma_mm(), e.orientation_sigma_deg());
        table.rows.push(vec![
            d.sensors[k].id.clone(),
            format!("{:.1}", e.position_mm.x),
            format!("{:.1}", e.position_mm.y),
            format!("{:.1}", e.position_mm.z),
            format!("{:.2}", sd.x),
            format!("{:.2}", sd.y),
            format!("{:.2}", sd.z),
            format!("{rot:.4}"),
            format!("{:.4}", e.model.get("f").unwrap_or(f64::NAN)),
            e.points.to_string(),
            format!("{:.0} %", 100.0 * r.diagnostics.coverage[k].fraction),
            format!("{:.2e}", e.rms_image_mm()),
        ]);
    }
    page.push(Block::Table(table));
    page.push(Block::Heading(
        "Coverage of each sensor's active area".into(),
    ));
    let mut figures = Vec::new();
    let kept: std::collections::HashSet<usize> = r
        .wands
        .iter()
        .enumerate()
        .filter(|w| w.1.is_some())
        .map(|w| w.0)
        .collect();
    for k in 0..d.sensors.len() {
        let g = d.sensors[k].geometry;
        let points: Vec<(f64, f64)> = d
            .observations
            .iter()
            .filter(|o| {
                o.sensor == k && (matches!(o.led, Led::Frame(_)) || kept.contains(&o.frame))
            })
            .step_by(3)
            .map(|o| (o.measured.x, o.measured.y))
            .collect();
        let set = [PointSet {
            label: d.sensors[k].id.clone(),
            points,
        }];
        let frame = Frame::sensor(&d.sensors[k].id, g.lx, g.ly);
        figures.push((
            coverage_svg(&set, g.lx, g.ly, &frame)?,
            format!(
                "{}: {:.0} % of the area",
                d.sensors[k].id,
                100.0 * r.diagnostics.coverage[k].fraction
            ),
        ));
    }
    page.push(Block::Figures(figures));
    page.push(Block::Heading("Wand-length residuals".into()));
    let residuals: Vec<f64> = r.diagnostics.frame_residuals.iter().map(|x| x.1).collect();
    if !residuals.is_empty() {
        page.push(Block::Figures(vec![(
            histogram_svg(&residuals, None, 30, "largest |wand-length error| per frame", "mm")?,
            "Each used frame's LEDs triangulated by the calibrated sensors alone; their distances against wand.csv.".into(),
        )]));
    }
    page.push(Block::List(
        r.diagnostics
            .worst_frames
            .iter()
            .map(|(f, e)| format!("frame {}: {e:.3} mm", d.frames[*f]))
            .collect(),
    ));
    page.push(Block::Heading("Diagnostics and advice".into()));
    page.push(Block::List(
        r.diagnostics
            .items
            .iter()
            .map(|i| format!("[{}] {}", i.code, i.message))
            .collect(),
    ));
    std::fs::create_dir_all(dir).map_err(|e| Error::OutputFolder {
        path: dir.to_path_buf(),
        message: format!("cannot create the report folder {}: {e}", dir.display()),
    })?;
    let path = dir.join(PAGE);
    psdcal_io::write_atomic_bytes(&path, page.render().as_bytes())?;
    folder.finish()?;
    Ok(path)
}
