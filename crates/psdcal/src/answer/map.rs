//! AoA and position error maps over the sensor area (the paper's Figure 9,
//! (P40)–(P42)): the table `psdcal map` writes.

use std::path::{Path, PathBuf};

use psdcal_locate::{error_map, ErrorSource, MapOptions, ParameterErrors};
use psdcal_model::{Param, PsdGeometry, SensorModel};

use crate::answer::loaded_sensor::LoadedSensor;
use crate::base::error::{Error, Result};
use crate::base::summary::{path_json, Summary};
use crate::base::table::{deg, empty, num, StatusCount, Table};
use psdcal_model::Stage as _;

/// Which model a map evaluates.
#[derive(Debug, Clone, PartialEq)]
pub enum MapModel {
    /// A calibration file (its model, sensor size and covariance).
    Calibration(PathBuf),
    /// The paper's simulated lens 1 or 2 on a 9 × 9 mm PSD.
    PaperLens(u8),
}

/// Where a map's errors come from.
#[derive(Debug, Clone, PartialEq)]
pub enum MapSource {
    /// Given parameter errors.
    Errors(Vec<(Param, f64)>),
    /// K standard deviations of the calibration's covariance.
    KSigma(f64),
}

impl MapSource {
    /// The source from `--error` lists (flattened) or `--k-sigma`: exactly
    /// one of the two, each parameter at most once.
    pub fn choose(
        errors: Vec<(Param, f64)>,
        k_sigma: Option<f64>,
    ) -> std::result::Result<Self, MapSourceError> {
        for (i, (p, _)) in errors.iter().enumerate() {
            if errors[..i].iter().any(|(q, _)| q == p) {
                return Err(MapSourceError::Repeated(*p));
            }
        }
        match (errors.is_empty(), k_sigma) {
            (false, None) => Ok(Self::Errors(errors)),
            (true, Some(k)) => Ok(Self::KSigma(k)),
            _ => Err(MapSourceError::Conflict),
        }
    }
}

/// Why [`MapSource::choose`] refused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MapSourceError {
    /// A parameter's error given twice.
    #[error("--error gives '{0}' twice; give each parameter once")]
    Repeated(Param),
    /// Both or neither of the errors and `--k-sigma`.
    #[error("give either --error NAME=VALUE or --k-sigma K, not both")]
    Conflict,
}

/// What to map.
#[derive(Debug, Clone, PartialEq)]
pub struct MapRequest {
    /// The model.
    pub model: MapModel,
    /// The errors.
    pub source: MapSource,
    /// Distance of the plane parallel to the sensor, mm.
    pub distance_mm: f64,
    /// Grid points per side.
    pub grid: usize,
    /// Add the paper's small-angle form (P42).
    pub paper: bool,
    /// Bounds on the files read whole (docs/formats.md, "Limits").
    pub limits: psdcal_io::ReadLimits,
}

/// A computed map.
#[derive(Debug, Clone)]
pub struct MapTable {
    /// The table.
    pub table: Table,
    /// Status counts and per-point warnings.
    pub count: StatusCount,
    /// The model, in words.
    pub model_name: String,
    /// The errors, in words.
    pub source_text: String,
    /// The active area mapped.
    pub geometry: PsdGeometry,
    /// Largest AoA error, degrees.
    pub max_aoa_deg: Option<f64>,
    /// Largest position error, mm.
    pub max_position_mm: Option<f64>,
}

impl MapTable {
    /// The summary of `map` for `request`, its table written to `out`
    /// (`None`: standard output): the largest errors and the rows' counts.
    pub fn summary(&self, request: &MapRequest, out: Option<&Path>) -> Summary {
        let json = serde_json::json!({
            "command": "map",
            "model": self.model_name,
            "errors": self.source_text,
            "grid": request.grid,
            "distance_mm": request.distance_mm,
            "out": path_json(out),
            "max_aoa_error_deg": self.max_aoa_deg,
            "max_position_error_mm": self.max_position_mm,
            "rows": self.count.to_json(),
        });
        let text = format!(
            "map: {}, {}, {n} x {n} grid over {lx} x {ly} mm, plane at {s} mm: largest AoA \
             error {aoa}°, largest position error {pos} mm; {counts}",
            self.model_name,
            self.source_text,
            n = request.grid,
            lx = self.geometry.lx,
            ly = self.geometry.ly,
            s = request.distance_mm,
            aoa = self.max_aoa_deg.map_or("-".into(), |v| format!("{v:.4}")),
            pos = self.max_position_mm.map_or("-".into(), |v| if v < 1e6 {
                format!("{v:.2}")
            } else {
                format!("{v:.3e}")
            }),
            counts = self.count.summary(),
        );
        Summary::new(text, json)
            .table_at(out)
            .warn(self.count.warning_lines())
    }
}

/// Computes the map of `request`.
pub fn map_table(request: &MapRequest) -> Result<MapTable> {
    let (model, geometry, covariance, model_name) = match &request.model {
        MapModel::Calibration(path) => {
            let loaded = LoadedSensor::read_with(path, request.limits)?;
            (
                loaded.sensor.model,
                loaded.sensor.geometry,
                // The map's own columns are not part of the error map's
                // model: its estimated parameters' covariance (the map's
                // uncertainty carried in) stays.
                Some(match &loaded.sensor.psd_map {
                    None => loaded.sensor.covariance,
                    Some(map) => {
                        let own: Vec<&str> = map
                            .stage
                            .parameters()
                            .iter()
                            .map(|p| p.name.as_str())
                            .collect();
                        let names: Vec<&str> = loaded
                            .sensor
                            .covariance
                            .names()
                            .iter()
                            .map(String::as_str)
                            .filter(|n| !own.contains(n))
                            .collect();
                        loaded
                            .sensor
                            .covariance
                            .sub(&names)
                            .map_err(|e| Error::Input(e.to_string()))?
                    }
                }),
                path.display().to_string(),
            )
        }
        MapModel::PaperLens(n) => (
            if *n == 1 {
                SensorModel::paper_lens1()
            } else {
                SensorModel::paper_lens2()
            },
            PsdGeometry::default(),
            None,
            format!("the paper's lens {n}"),
        ),
    };
    let source = match (&request.source, covariance) {
        (MapSource::Errors(errors), _) => {
            ErrorSource::Parameters(ParameterErrors::new(errors.clone())?)
        }
        (MapSource::KSigma(k), Some(covariance)) => {
            if covariance.is_empty() {
                return Err(Error::Input(format!(
                    "{model_name} has no covariance (nothing was estimated), so a k-sigma map \
                     would be zero everywhere; give parameter errors with --error NAME=VALUE"
                )));
            }
            ErrorSource::Covariance { covariance, k: *k }
        }
        (MapSource::KSigma(_), None) => {
            return Err(Error::Options("--k-sigma needs --calibration".into()))
        }
    };
    let options = MapOptions {
        grid: request.grid,
        distance_mm: request.distance_mm,
        paper_form: request.paper,
    };
    let map = error_map(&model, &geometry, &source, &options)?;
    let mut header: Vec<String> = [
        "x_mm",
        "y_mm",
        "alpha_x_deg",
        "alpha_y_deg",
        "aoa_error_x_deg",
        "aoa_error_y_deg",
        "aoa_error_deg",
        "position_error_x_mm",
        "position_error_y_mm",
        "position_error_mm",
    ]
    .into_iter()
    .map(String::from)
    .collect();
    if request.paper {
        header.extend([
            "paper_aoa_error_x_deg".into(),
            "paper_aoa_error_y_deg".into(),
        ]);
    }
    header.push("status".into());
    let mut count = StatusCount::default();
    let mut rows = Vec::with_capacity(map.cells.len());
    for cell in &map.cells {
        let mut out = vec![num(cell.measured.x), num(cell.measured.y)];
        match &cell.values {
            Ok(v) => {
                out.extend([
                    deg(v.alpha.x),
                    deg(v.alpha.y),
                    deg(v.aoa_error.x),
                    deg(v.aoa_error.y),
                    deg(v.aoa_error_total),
                    num(v.position_error.x),
                    num(v.position_error.y),
                    num(v.position_error_total),
                ]);
                if let Some(p) = v.paper_aoa_error {
                    out.extend([deg(p.x), deg(p.y)]);
                }
                out.push("ok".into());
                count.answered("ok", None);
            }
            Err(e) => {
                out.extend(empty(header.len() - 3));
                out.push(e.status().to_string());
                count.failed(
                    e,
                    &format!("grid point ({}, {}) mm", cell.measured.x, cell.measured.y),
                );
            }
        }
        rows.push(out);
    }
    refuse_unusable_map(&map, &count)?;
    let source_text = match &request.source {
        MapSource::Errors(e) => e
            .iter()
            .map(|(p, v)| format!("Δ{p} = {v}"))
            .collect::<Vec<_>>()
            .join(", "),
        MapSource::KSigma(k) => format!("{k} σ of the calibration's covariance"),
    };
    Ok(MapTable {
        table: Table { header, rows },
        count,
        model_name,
        source_text,
        geometry,
        max_aoa_deg: map.max_aoa_error().map(f64::to_degrees),
        max_position_mm: map.max_position_error(),
    })
}

/// A map whose every grid point fails, or whose values overflow, is an
/// error: the request (parameter errors, k, distance) cannot be mapped.
fn refuse_unusable_map(map: &psdcal_locate::ErrorMap, count: &StatusCount) -> Result<()> {
    if count.unanswered() == count.rows() {
        let first = count.warnings.first().cloned().unwrap_or_default();
        return Err(Error::Options(format!(
            "no grid point can be mapped ({first}); give parameter errors that keep the model \
             valid (e.g. |Δf| below f) or a smaller --k-sigma"
        )));
    }
    let overflow = map.cells.iter().any(|cell| match &cell.values {
        Ok(v) => ![
            v.alpha.x,
            v.alpha.y,
            v.aoa_error.x,
            v.aoa_error.y,
            v.aoa_error_total,
            v.position_error.x,
            v.position_error.y,
            v.position_error_total,
        ]
        .iter()
        .all(|x| x.is_finite()),
        Err(_) => false,
    });
    if overflow {
        return Err(Error::Options(
            "the map's errors overflow (not finite numbers); give a smaller --distance, \
             --k-sigma or parameter errors"
                .to_string(),
        ));
    }
    Ok(())
}
