//! The paper's Figure 9: how large the angle-of-arrival and position errors
//! are across the sensor when the parameters are off by what the Monte Carlo
//! study found (docs/model.md §5).
//!
//! For each condition of Tables 9–10 the parameters are set to
//! `θ = θ_ideal + Δθ` with `Δθ = |mean − ideal| + 2·std` for `Cx, Cy, f, k1,
//! k2` (every offset positive, so their effects add). Over a 41 × 41 grid of
//! measured points on the active area, the ray of the true model and the ray
//! of the perturbed one are compared: the AoA error is the angle between
//! them, and the position error is their distance on a plane parallel to the
//! sensor at `S = 5 m` (`P = S·(a, b, 1)` for a normalised ray `(a, b)`). The
//! full model is used, not the small-angle sensitivity (P40)–(P42).
//!
//! The map itself is psdcal-locate's [`psdcal_locate::error_map`] (the one
//! definition, also behind `psdcal map`); this module chooses the offsets and
//! keeps each map's summary in the study's units (degrees, mm).

use psdcal_locate::{ErrorSource, MapOptions, ParameterErrors};
use psdcal_model::{Param, PsdGeometry, SensorModel};
use serde::Serialize;

use crate::study::{Quantity, TableResult};

/// Distance of the plane of Figure 9, mm.
pub const FIG9_DISTANCE_MM: f64 = 5000.0;
/// Grid points per side.
pub const FIG9_GRID: usize = 41;

/// One map of Figure 9: a condition's offsets and the resulting errors.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Figure9Map {
    /// The lens (1 or 2).
    pub lens: u8,
    /// The condition (column of Table 9 or 10).
    pub condition: String,
    /// The parameter offsets used, `(name, Δ)`.
    pub offsets: Vec<(String, f64)>,
    /// `(x_mm, y_mm, aoa_error_deg, position_error_mm)` per grid point, `y`
    /// outer (points where either model gives no ray are left out).
    pub grid: Vec<[f64; 4]>,
    /// Largest AoA error, degrees.
    pub max_aoa_deg: f64,
    /// Largest position error at 5 m, mm.
    pub max_position_mm: f64,
    /// Mean AoA error, degrees.
    pub mean_aoa_deg: f64,
}

/// The maps of Figure 9 from the results of Tables 9 and 10 (either may be
/// missing).
pub fn figure9(tables: &[TableResult], geometry: &PsdGeometry) -> Vec<Figure9Map> {
    let mut maps = Vec::new();
    for table in tables
        .iter()
        .filter(|t| t.spec.id == "table9" || t.spec.id == "table10")
    {
        for column in &table.columns {
            let c = &column.condition;
            let mut truth = c.lens.model();
            if c.psd_distortion {
                truth.distortion.l1 = SensorModel::PAPER_L1;
            }
            let mut perturbed = truth;
            let mut offsets = Vec::new();
            for (q, p) in [
                (Quantity::Cx, Param::Cx),
                (Quantity::Cy, Param::Cy),
                (Quantity::F, Param::F),
                (Quantity::K1, Param::K1),
                (Quantity::K2, Param::K2),
            ] {
                let row = table.rows.iter().position(|r| *r == q);
                let (Some(row), Some(ideal)) = (row, c.ideal(q)) else {
                    continue;
                };
                let Some(s) = column.stats[row] else { continue };
                let delta = (s.mean - ideal).abs() + 2.0 * s.std;
                // k1's ideal here is k1 + l1 (what the fit estimates); offset k1.
                perturbed.set(p, truth.get(p) + delta);
                offsets.push((p.name().to_string(), delta));
            }
            maps.push(error_map(
                c.lens.number(),
                &c.label,
                &truth,
                &perturbed,
                geometry,
                offsets,
            ));
        }
    }
    maps
}

/// The AoA and position error map between `truth` and `perturbed` over the
/// sensor: psdcal-locate's error map of `truth` with the parameter errors
/// `perturbed − truth`, on the Figure's grid and plane.
pub fn error_map(
    lens: u8,
    condition: &str,
    truth: &SensorModel,
    perturbed: &SensorModel,
    geometry: &PsdGeometry,
    offsets: Vec<(String, f64)>,
) -> Figure9Map {
    let errors: Vec<(Param, f64)> = Param::ALL
        .iter()
        .map(|&p| (p, perturbed.get(p) - truth.get(p)))
        .filter(|(_, d)| *d != 0.0)
        .collect();
    let options = MapOptions {
        grid: FIG9_GRID,
        distance_mm: FIG9_DISTANCE_MM,
        paper_form: false,
    };
    let map = ParameterErrors::new(errors).and_then(|e| {
        psdcal_locate::error_map(truth, geometry, &ErrorSource::Parameters(e), &options)
    });
    let grid: Vec<[f64; 4]> = map
        .iter()
        .flat_map(|m| &m.cells)
        .filter_map(|cell| {
            let v = cell.values.as_ref().ok()?;
            let row = [
                cell.measured.x,
                cell.measured.y,
                v.aoa_error_total.to_degrees(),
                v.position_error_total,
            ];
            row.iter().all(|x| x.is_finite()).then_some(row)
        })
        .collect();
    let max_aoa_deg = grid.iter().map(|g| g[2]).fold(0.0, f64::max);
    let max_position_mm = grid.iter().map(|g| g[3]).fold(0.0, f64::max);
    let mean_aoa_deg = grid.iter().map(|g| g[2]).sum::<f64>() / grid.len().max(1) as f64;
    Figure9Map {
        lens,
        condition: condition.into(),
        offsets,
        grid,
        max_aoa_deg,
        max_position_mm,
        mean_aoa_deg,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A focal-length offset on a distortion-free pinhole: at a measured
    /// point at radius `r` from the centre the two rays make the angles
    /// `atan(r/f)` and `atan(r/(f + Δf))` with the axis (same azimuth), and
    /// meet the plane at `S r/f` and `S r/(f + Δf)`.
    #[test]
    fn focal_offset_map_matches_the_closed_form() {
        let truth = SensorModel::pinhole(8.0, 0.0, 0.0);
        let mut perturbed = truth;
        let df = 0.04;
        perturbed.set(Param::F, truth.get(Param::F) + df);
        let geometry = PsdGeometry::default();
        let map = error_map(
            2,
            "test",
            &truth,
            &perturbed,
            &geometry,
            vec![("f".into(), df)],
        );
        assert_eq!(map.grid.len(), FIG9_GRID * FIG9_GRID);
        let (f, s) = (8.0, FIG9_DISTANCE_MM);
        for [x, y, aoa_deg, position_mm] in &map.grid {
            let r = x.hypot(*y);
            let angle = ((r / f).atan() - (r / (f + df)).atan()).to_degrees();
            let position = s * r * (1.0 / f - 1.0 / (f + df));
            assert!(
                (aoa_deg - angle).abs() <= 1e-12,
                "({x}, {y}): {aoa_deg} vs {angle}"
            );
            assert!((position_mm - position).abs() <= 1e-9, "({x}, {y})");
        }
        // The corner is the worst point: r = 4.5·√2 mm.
        let r = 4.5 * 2f64.sqrt();
        let corner = s * r * (1.0 / f - 1.0 / (f + df));
        assert!((map.max_position_mm - corner).abs() <= 1e-9);
    }
}
