//! The residual map: a fit's residuals summarised on a grid of cells over
//! the map's frame, `rms = √(mean |r_i|²)` and `mean = Σ r_i / n` of the
//! points in each cell (for reports: where the map fits worse than the
//! noise, and whether it leaves a systematic pattern).

use nalgebra::Vector2;
use psdcal_model::stages::MapFrame;

/// One cell of the residual map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResidualCell {
    /// Column (along x) and row (along y), from the frame's lower-left.
    pub column: usize,
    /// Row.
    pub row: usize,
    /// Cell centre, mm.
    pub centre: Vector2<f64>,
    /// Points in the cell.
    pub points: usize,
    /// RMS residual of its points, mm (0 when empty).
    pub rms_mm: f64,
    /// Mean residual of its points, mm (0 when empty).
    pub mean_mm: Vector2<f64>,
}

/// The residuals of points `measured` on `cells × cells` cells of `frame`
/// (row-major from the lower-left; points outside the frame go to the
/// nearest cell).
pub fn residual_map(
    frame: &MapFrame,
    measured: &[Vector2<f64>],
    residuals: &[Vector2<f64>],
    cells: usize,
) -> Vec<ResidualCell> {
    let cells = cells.max(1);
    let size = frame.max - frame.min;
    let mut sum = vec![(0usize, 0.0f64, Vector2::zeros()); cells * cells];
    let cell = |t: f64| ((t * cells as f64).floor().max(0.0) as usize).min(cells - 1);
    for (m, r) in measured.iter().zip(residuals) {
        let (i, j) = (
            cell((m.x - frame.min.x) / size.x),
            cell((m.y - frame.min.y) / size.y),
        );
        let s = &mut sum[j * cells + i];
        s.0 += 1;
        s.1 += r.norm_squared();
        s.2 += r;
    }
    (0..cells * cells)
        .map(|k| {
            let (i, j) = (k % cells, k / cells);
            let (count, s, total) = sum[k];
            ResidualCell {
                column: i,
                row: j,
                centre: Vector2::new(
                    frame.min.x + size.x * (i as f64 + 0.5) / cells as f64,
                    frame.min.y + size.y * (j as f64 + 0.5) / cells as f64,
                ),
                points: count,
                rms_mm: if count > 0 {
                    (s / count as f64).sqrt()
                } else {
                    0.0
                },
                mean_mm: if count > 0 {
                    total / count as f64
                } else {
                    Vector2::zeros()
                },
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_hold_their_points_rms_and_mean() {
        // Frame [0, 2] × [0, 2] in 2 × 2 cells: three points in the lower-left
        // cell, one in the upper-right, none elsewhere.
        let frame = MapFrame {
            min: Vector2::new(0.0, 0.0),
            max: Vector2::new(2.0, 2.0),
        };
        let measured = [
            Vector2::new(0.2, 0.3),
            Vector2::new(0.9, 0.1),
            Vector2::new(0.5, 0.5),
            Vector2::new(1.5, 1.9),
        ];
        let residuals = [
            Vector2::new(1.0, 0.0),
            Vector2::new(0.0, 2.0),
            Vector2::new(-1.0, 1.0),
            Vector2::new(3.0, 4.0),
        ];
        let cells = residual_map(&frame, &measured, &residuals, 2);
        assert_eq!(cells.len(), 4);
        let c = &cells[0];
        assert_eq!((c.column, c.row, c.points), (0, 0, 3));
        assert!((c.rms_mm - (7.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!((c.mean_mm - Vector2::new(0.0, 1.0)).norm() < 1e-15);
        assert_eq!(c.centre, Vector2::new(0.5, 0.5));
        let d = &cells[3];
        assert_eq!((d.column, d.row, d.points), (1, 1, 1));
        assert!((d.rms_mm - 5.0).abs() < 1e-15);
        assert_eq!(d.mean_mm, Vector2::new(3.0, 4.0));
        assert!(cells[1].points == 0 && cells[1].rms_mm == 0.0);
        assert_eq!(cells[2].mean_mm, Vector2::zeros());
    }
}
