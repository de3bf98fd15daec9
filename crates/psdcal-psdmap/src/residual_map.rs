//! The residual map: a fit's residuals summarised on a grid of cells over
//! the map's frame, `rms = √(mean |r_i|²)` of the points in each cell (for
//! reports: where the map fits worse than the noise).

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
    let mut sum = vec![(0usize, 0.0f64); cells * cells];
    let cell = |t: f64| ((t * cells as f64).floor().max(0.0) as usize).min(cells - 1);
    for (m, r) in measured.iter().zip(residuals) {
        let (i, j) = (
            cell((m.x - frame.min.x) / size.x),
            cell((m.y - frame.min.y) / size.y),
        );
        sum[j * cells + i].0 += 1;
        sum[j * cells + i].1 += r.norm_squared();
    }
    (0..cells * cells)
        .map(|k| {
            let (i, j) = (k % cells, k / cells);
            let (count, s) = sum[k];
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
            }
        })
        .collect()
}
