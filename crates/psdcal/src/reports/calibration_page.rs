//! A calibration report: its content (tables, plot data and captions) from
//! a calibration and, optionally, its data; psdcal-report draws it; the
//! page and every plot (SVG and PNG) are written into one folder.

use std::path::{Path, PathBuf};

use psdcal_io::{write_atomic_bytes, Warning};
use psdcal_locate::{error_map, ErrorSource, MapOptions};
use psdcal_model::Model;
use psdcal_report::{calibration_page, CalibrationReport, Frame, HeatCell, Plot, PlotData};

use crate::answer::loaded_sensor::LoadedSensor;
use crate::base::error::{Error, Result};
use crate::calibration::residuals::ResidualTable;
use crate::dataset::data_set::{DataSet, DataSetFiles, LoadOptions, PointSource};
use crate::reports::calibration_plots::{data_plots, model_plots, region_boundary, region_text};
use crate::reports::calibration_tables::{residual_rows, tables, worst_points, Sources};

/// Grid points per side of the error maps.
const MAP_GRID: usize = 21;
/// Standard deviations of the error maps.
const MAP_K: f64 = 2.0;

/// What to report.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReportRequest {
    /// calibration.json.
    pub calibration: PathBuf,
    /// `(template, observations)` of the calibration data.
    pub data: Option<(PathBuf, PathBuf)>,
    /// Output folder.
    pub out: PathBuf,
    /// Bounds on the files read whole (docs/formats.md, "Limits").
    pub limits: psdcal_io::ReadLimits,
    /// Replace files in `out` that psdcal did not write there
    /// (docs/formats.md, "Output folders").
    pub force: bool,
}

/// What a report wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportFiles {
    /// report.html.
    pub html: PathBuf,
    /// The plots' names.
    pub plots: Vec<&'static str>,
    /// Every file written.
    pub files: Vec<PathBuf>,
    /// What was dropped from the data.
    pub warnings: Vec<Warning>,
}

impl ReportFiles {
    /// The summary of a report written into the folder `out`.
    pub fn summary(&self, out: &std::path::Path) -> crate::base::summary::Summary {
        let files: Vec<String> = self.files.iter().map(|f| f.display().to_string()).collect();
        let json = serde_json::json!({
            "report": self.html.display().to_string(),
            "plots": self.plots,
            "files": files,
        });
        let text = format!(
            "wrote {} and {} plots (SVG and PNG) into {}",
            self.html.display(),
            self.plots.len(),
            out.display()
        );
        crate::base::summary::Summary::new(text, json).warn(&self.warnings)
    }
}

/// Builds and writes the report.
pub fn write_report(request: &ReportRequest) -> Result<ReportFiles> {
    let loaded = LoadedSensor::read_with(&request.calibration, request.limits)?;
    let geometry = loaded.record.geometry();
    let data = match &request.data {
        Some((t, o)) => Some(DataSet::from_files(
            &DataSetFiles {
                template: t.clone(),
                points: PointSource::Observations(o.clone()),
                gains: None,
            },
            &LoadOptions {
                geometry,
                strict: false,
                limits: request.limits,
            },
        )?),
        None => None,
    };
    let content = report_content(request, &loaded, data.as_ref())?;
    let svgs: Vec<String> = content
        .plots
        .iter()
        .map(Plot::svg)
        .collect::<Result<_, _>>()
        .map_err(|_| {
            Error::Input(format!(
                "{}: the report cannot be drawn from this calibration: its parameters give \
                 values that are not finite numbers; check its values or calibrate again",
                request.calibration.display()
            ))
        })?;
    let names: Vec<String> = std::iter::once(PathBuf::from(REPORT_PAGE))
        .chain(plot_files(Path::new(""), &content.plots))
        .map(|p| p.display().to_string())
        .collect();
    // The folder is created only once the page can be drawn: a failure
    // leaves nothing behind.
    std::fs::create_dir_all(&request.out).map_err(|e| Error::OutputFolder {
        path: request.out.clone(),
        message: format!(
            "cannot create the output folder {}: {e}",
            request.out.display()
        ),
    })?;
    let folder = psdcal_io::OutputFolder::claim(&request.out, &names, request.force)?;
    let page = calibration_page(&content, &svgs);
    let html = request.out.join(REPORT_PAGE);
    write_atomic_bytes(&html, page.render().as_bytes())?;
    let mut files = vec![html.clone()];
    files.extend(write_plots(&request.out, &content.plots, &svgs)?);
    folder.finish()?;
    Ok(ReportFiles {
        html,
        plots: content.plots.iter().map(|p| p.name).collect(),
        files,
        warnings: data.map(|d| d.validated.warnings).unwrap_or_default(),
    })
}

/// The report's page in its folder.
const REPORT_PAGE: &str = "report.html";

/// Writes each plot into `dir` as `NAME.svg` (its SVG text from `svgs`,
/// in order) and `NAME.png`, both atomically; the files written.
pub(crate) fn write_plots(dir: &Path, plots: &[Plot], svgs: &[String]) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for (plot, svg) in plots.iter().zip(svgs) {
        let svg_path = dir.join(format!("{}.svg", plot.name));
        write_atomic_bytes(&svg_path, svg.as_bytes())?;
        let png_path = dir.join(format!("{}.png", plot.name));
        // A temporary file of its own (two reports into one folder never
        // share one), removed if drawing fails.
        psdcal_io::write_atomic_at(&png_path, |tmp| plot.png(tmp))?;
        files.push(svg_path);
        files.push(png_path);
    }
    Ok(files)
}

/// The files [`write_plots`] writes for `plots` into `dir`.
pub(crate) fn plot_files(dir: &Path, plots: &[Plot]) -> Vec<PathBuf> {
    plots
        .iter()
        .flat_map(|p| ["svg", "png"].map(|e| dir.join(format!("{}.{e}", p.name))))
        .collect()
}

/// The report's content.
pub fn report_content(
    request: &ReportRequest,
    loaded: &LoadedSensor,
    data: Option<&DataSet>,
) -> Result<CalibrationReport> {
    let calibration = &loaded.record;
    let model = &loaded.sensor.model;
    let geometry = loaded.record.geometry();
    let (lx, ly) = (geometry.lx, geometry.ly);
    let mut plots = Vec::new();
    let mut recomputed = None;
    let mut worst = None;
    let mut warnings = Vec::new();
    if let Some(set) = data {
        warnings.extend(set.validated.warnings.iter().map(|w| format!("data: {w}")));
        let poses: Vec<(&str, psdcal_model::Pose)> = calibration
            .images
            .iter()
            .map(|i| (i.id.as_str(), i.pose()))
            .collect();
        let table =
            ResidualTable::compute(&Model::from(model), &poses, &set.template, &set.validated);
        recomputed = Some(residual_rows(&table));
        worst = Some(worst_points(&table, &set.template));
        data_plots(&mut plots, set, &table, lx, ly);
        plots.extend(crate::reports::calibration_views::pose_plot(
            calibration,
            &set.template,
        ));
    }
    let region = &loaded.sensor.valid_region;
    if let (false, Some(coverage)) = (region.whole_active_area(), plots.first_mut()) {
        if let PlotData::Coverage { sets, .. } = &mut coverage.data {
            sets.push(region_boundary(region));
        }
    }
    model_plots(&mut plots, model, region, lx, ly);
    let psd_map = calibration.psd_map.as_ref();
    plots.extend(crate::reports::calibration_views::map_plots(
        &loaded.sensor,
        psd_map.and_then(|m| m.scan.as_ref()),
    ));
    if !loaded.sensor.covariance.is_empty() {
        let map = error_map(
            model,
            &geometry,
            &ErrorSource::Covariance {
                covariance: loaded.sensor.covariance.clone(),
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
            plots.push(Plot {
                name,
                caption: format!(
                    "{title} from the calibration's covariance over the active area, largest {max:.4} {} (paper Figure 9)",
                    if position { "mm" } else { "deg" }
                ),
                data: PlotData::HeatMap {
                    cells,
                    step,
                    frame: Frame::sensor(title, lx, ly),
                    label: label.to_string(),
                },
            });
        }
    }
    let mut report = tables(
        Sources::new(&request.calibration, request.data.as_ref(), calibration),
        calibration,
        model,
        plots,
        recomputed,
        worst,
        warnings,
    );
    report.sources.push(region_text(region));
    report
        .sources
        .extend(psd_map.map(crate::reports::calibration_views::map_text));
    Ok(report)
}
