//! calibration.json version 2's `psd_map` stage (docs/formats.md,
//! docs/model.md §8.3): the PSD's non-linearity map, first among the
//! distortion stages, held fixed in the calibration or refined with its
//! scan as the prior (`calibrate --refine-psd-map`).
//!
//! `{"kind": "psd_map", "parameters": {"map_x_0_0": …}, "estimated": [],
//! "configuration": {basis, order or cells, frame_mm, hull_mm},
//! "covariance": {"sigma_x_mm", "sigma_y_mm", "unit": K×K, "cross": 2K rows
//! × the calibration's covariance names}}`. The map's own covariance is
//! `σ_x² U` (x coefficients), `σ_y² U` (y); `cross` is its covariance with
//! the calibration's estimated parameters (the map's error carried into
//! them, docs/model.md §8.3), whose `covariance` already includes it. Its
//! coefficients live in the stage only, not in the flat `parameters`.
//!
//! A refined map lists all its parameters in `estimated` and carries
//! `covariance.matrix` (2K × 2K, the stage's parameter order): its
//! coefficients' covariance from the joint information of the calibration
//! data and the scan (`sigma_x_mm`, `sigma_y_mm`, `unit` stay the scan's,
//! the prior); `cross` is then the refined coefficients' covariance with the
//! other estimated parameters.
//!
//! `scan` (optional; calibrations of older psdcal lack it, and older
//! readers ignore it) summarises the scan the map was fitted to, for the
//! report: `model`, `fit` (psd_map.json's `fit`), and `residual_cells`: the
//! scan's residuals (stage position minus corrected point, outliers left
//! out) on `cells × cells` cells of the stage's `frame_mm`, per non-empty
//! cell its centre, point count, mean residual and RMS residual in µm.

use nalgebra::DMatrix;
use psdcal_model::stages::PsdMap;
use psdcal_model::{ParameterCovariance, Stage};
use serde::{Deserialize, Serialize};

use crate::MapFitRecord;

/// The map's covariance as stored in its stage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PsdMapStageCovariance {
    /// Scan noise along x, mm.
    pub sigma_x_mm: f64,
    /// Scan noise along y, mm.
    pub sigma_y_mm: f64,
    /// `U` (K×K).
    pub unit: Vec<Vec<f64>>,
    /// Covariance of the map's coefficients (rows, the stage's parameter
    /// order) with the calibration's estimated parameters (columns, the
    /// order of `covariance.parameters`).
    pub cross: Vec<Vec<f64>>,
    /// A refined map's coefficients' covariance (2K × 2K, the stage's
    /// parameter order); absent for a map held fixed (then `σ² U`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub matrix: Option<Vec<Vec<f64>>>,
}

/// The scan's residuals per cell (columns, one entry per non-empty cell).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScanResidualCells {
    /// Cells per side over the stage's frame.
    pub cells: usize,
    /// Cell centres, mm.
    pub x_mm: Vec<f64>,
    /// Cell centres, mm.
    pub y_mm: Vec<f64>,
    /// Scan points in each cell.
    pub points: Vec<usize>,
    /// Mean residual along x, µm.
    pub dx_um: Vec<f64>,
    /// Mean residual along y, µm.
    pub dy_um: Vec<f64>,
    /// RMS residual (of `|r|`), µm.
    pub rms_um: Vec<f64>,
}

/// The summary of the scan a calibration's map was fitted to.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PsdMapScanRecord {
    /// The map's model (`poly:N`, `spline:N`).
    pub model: String,
    /// The fit's summary, as psd_map.json's `fit`.
    pub fit: MapFitRecord,
    /// The residuals per cell.
    pub residual_cells: ScanResidualCells,
}

impl PsdMapScanRecord {
    /// One value per cell in every column, finite numbers, non-empty cells.
    pub fn check(&self) -> Result<(), String> {
        let c = &self.residual_cells;
        let n = c.x_mm.len();
        let columns = [&c.y_mm, &c.dx_um, &c.dy_um, &c.rms_um];
        if c.cells == 0
            || c.points.len() != n
            || columns.iter().any(|v| v.len() != n)
            || n > c.cells * c.cells
        {
            return Err(
                "the psd_map stage's scan.residual_cells: 'cells' must be at least 1 and x_mm, \
                 y_mm, points, dx_um, dy_um, rms_um hold one value per cell (at most cells²)"
                    .into(),
            );
        }
        let f = &self.fit;
        let finite = columns
            .iter()
            .chain([&&c.x_mm])
            .all(|v| v.iter().all(|x| x.is_finite()))
            && c.rms_um.iter().all(|v| *v >= 0.0)
            && c.points.iter().all(|p| *p > 0)
            && [
                f.cv_rms_um,
                f.rms_um,
                f.sigma_x_um,
                f.sigma_y_um,
                f.map_sigma_um,
            ]
            .iter()
            .all(|v| v.is_finite() && *v >= 0.0);
        if !finite {
            return Err(
                "the psd_map stage's scan: its numbers must be finite, RMS values and sigmas \
                 not negative, every cell with points"
                    .into(),
            );
        }
        Ok(())
    }
}

/// A calibration's PSD map.
#[derive(Debug, Clone, PartialEq)]
pub struct PsdMapStageRecord {
    /// The stage's structure ([`Stage::configuration`]).
    pub configuration: serde_json::Value,
    /// Coefficients by name, in the stage's order.
    pub parameters: Vec<(String, f64)>,
    /// Their covariance.
    pub covariance: PsdMapStageCovariance,
    /// Whether the calibration refined the coefficients (then
    /// `covariance.matrix` is theirs).
    pub estimated: bool,
    /// The scan's summary, when the calibration stored it.
    pub scan: Option<PsdMapScanRecord>,
}

impl PsdMapStageRecord {
    /// The stage and its block, checked: the names must be the stage's, in
    /// its order, every number finite, the covariance of the right sizes.
    pub fn to_stage(&self, estimated: usize) -> Result<(PsdMap, Vec<f64>), String> {
        let stage = PsdMap::from_configuration(&self.configuration).map_err(|e| e.to_string())?;
        let names: Vec<&str> = stage.parameters().iter().map(|p| p.name.as_str()).collect();
        let given: Vec<&str> = self.parameters.iter().map(|(n, _)| n.as_str()).collect();
        if names != given {
            return Err(format!(
                "the psd_map stage's parameters must be the {} coefficients of {} in order \
                 ({} …)",
                names.len(),
                stage.basis().label(),
                names.iter().take(3).copied().collect::<Vec<_>>().join(", ")
            ));
        }
        let block: Vec<f64> = self.parameters.iter().map(|(_, v)| *v).collect();
        let c = &self.covariance;
        let k = stage.terms();
        let finite = block.iter().all(|v| v.is_finite())
            && [c.sigma_x_mm, c.sigma_y_mm]
                .iter()
                .all(|v| v.is_finite() && *v >= 0.0);
        if !finite {
            return Err("the psd_map stage's coefficients and sigmas must be finite".into());
        }
        let square = |m: &Vec<Vec<f64>>, rows: usize, cols: usize| {
            m.len() == rows
                && m.iter()
                    .all(|r| r.len() == cols && r.iter().all(|v| v.is_finite()))
        };
        if self.estimated != c.matrix.is_some() {
            return Err(
                "the psd_map stage's covariance: a refined map (its parameters in \
                 'estimated') carries 'matrix', a fixed one does not"
                    .into(),
            );
        }
        if c.matrix.as_ref().is_some_and(|m| !square(m, 2 * k, 2 * k)) {
            return Err(format!(
                "the psd_map stage's covariance: 'matrix' must be {0} × {0}, of finite numbers",
                2 * k
            ));
        }
        if !square(&c.unit, k, k) || !square(&c.cross, 2 * k, estimated) {
            return Err(format!(
                "the psd_map stage's covariance: 'unit' must be {k} × {k} and 'cross' {} × \
                 {estimated}, of finite numbers",
                2 * k
            ));
        }
        Ok((stage, block))
    }

    /// The map's own covariance by its names.
    pub fn map_covariance(&self, stage: &PsdMap) -> Result<ParameterCovariance, String> {
        let k = stage.terms();
        let c = &self.covariance;
        let names: Vec<String> = stage.parameters().iter().map(|p| p.name.clone()).collect();
        if let Some(matrix) = &c.matrix {
            let m = DMatrix::from_fn(2 * k, 2 * k, |i, j| matrix[i][j]);
            return ParameterCovariance::new(names, m)
                .map_err(|e| format!("the psd_map stage's covariance.matrix: {e}"));
        }
        let unit = DMatrix::from_fn(k, k, |i, j| c.unit[i][j]);
        let mut m = DMatrix::zeros(2 * k, 2 * k);
        m.view_mut((0, 0), (k, k))
            .copy_from(&(&unit * c.sigma_x_mm.powi(2)));
        m.view_mut((k, k), (k, k))
            .copy_from(&(&unit * c.sigma_y_mm.powi(2)));
        ParameterCovariance::new(names, m)
            .map_err(|e| format!("the psd_map stage's covariance: {e}"))
    }
}
