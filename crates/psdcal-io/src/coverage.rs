//! How much of the sensor a data set covers.
//!
//! The active area `Lx × Ly`, centred on the electrical centre, is divided
//! into an `n × n` grid of equal cells (10 × 10 by default); a cell is
//! covered when at least one point falls in it (points on a cell border go to
//! the cell on their +x / −y side; points on the outer border to the edge
//! cell). Rows are stored top first, i.e. from +y to −y, as the sensor is
//! drawn. A well-spread data set covers most cells: distortion is only
//! constrained where there are points.

use nalgebra::Vector2;
use psdcal_model::PsdGeometry;
use serde::Serialize;

/// Smallest axis-aligned box holding a set of points, mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bounds {
    /// Smallest x, mm.
    pub x_min_mm: f64,
    /// Largest x, mm.
    pub x_max_mm: f64,
    /// Smallest y, mm.
    pub y_min_mm: f64,
    /// Largest y, mm.
    pub y_max_mm: f64,
}

impl Bounds {
    /// The bounding box of `points`, `None` when there are none.
    pub fn of<'a>(points: impl IntoIterator<Item = &'a Vector2<f64>>) -> Option<Self> {
        points.into_iter().fold(None, |acc, p| {
            Some(match acc {
                None => Bounds {
                    x_min_mm: p.x,
                    x_max_mm: p.x,
                    y_min_mm: p.y,
                    y_max_mm: p.y,
                },
                Some(b) => Bounds {
                    x_min_mm: b.x_min_mm.min(p.x),
                    x_max_mm: b.x_max_mm.max(p.x),
                    y_min_mm: b.y_min_mm.min(p.y),
                    y_max_mm: b.y_max_mm.max(p.y),
                },
            })
        })
    }
}

/// Coverage of the active area by a set of points.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Coverage {
    /// Cells per side of the grid.
    pub cells_per_side: usize,
    /// Number of cells holding at least one point.
    pub cells_covered: usize,
    /// `cells_covered / cells_per_side²`.
    pub fraction: f64,
    /// Bounding box of all points.
    pub bounds: Option<Bounds>,
    /// Points per cell; row 0 is the top (+y) row, column 0 the −x side.
    pub counts: Vec<Vec<usize>>,
}

impl Coverage {
    /// The default grid: 10 × 10 cells.
    pub const DEFAULT_CELLS: usize = 10;

    /// Coverage of `geometry`'s active area by `points`, on a grid of
    /// `cells_per_side` × `cells_per_side` cells (at least 1). Points off the
    /// area count for the bounding box only.
    pub fn of<'a>(
        points: impl IntoIterator<Item = &'a Vector2<f64>> + Clone,
        geometry: &PsdGeometry,
        cells_per_side: usize,
    ) -> Self {
        let n = cells_per_side.max(1);
        let mut counts = vec![vec![0usize; n]; n];
        let cell = |offset: f64, side: f64| -> Option<usize> {
            let u = offset / side;
            if (0.0..=1.0).contains(&u) {
                // `u` is in [0, 1], so the product is in [0, n] and fits.
                Some(((u * n as f64).floor() as usize).min(n - 1))
            } else {
                None
            }
        };
        for p in points.clone() {
            let column = cell(p.x + 0.5 * geometry.lx, geometry.lx);
            let row = cell(0.5 * geometry.ly - p.y, geometry.ly);
            if let (Some(column), Some(row)) = (column, row) {
                if let Some(count) = counts.get_mut(row).and_then(|r| r.get_mut(column)) {
                    *count += 1;
                }
            }
        }
        let cells_covered = counts.iter().flatten().filter(|&&c| c > 0).count();
        Self {
            cells_per_side: n,
            cells_covered,
            fraction: cells_covered as f64 / (n * n) as f64,
            bounds: Bounds::of(points),
            counts,
        }
    }

    /// The grid as text, top row first: `#` for a covered cell, `.` for an
    /// empty one.
    pub fn ascii_map(&self) -> Vec<String> {
        self.counts
            .iter()
            .map(|row| row.iter().map(|&c| if c > 0 { '#' } else { '.' }).collect())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds() {
        assert_eq!(Bounds::of(&[]), None);
        let pts = [
            Vector2::new(1.0, -2.0),
            Vector2::new(-3.0, 0.5),
            Vector2::new(0.0, 4.0),
        ];
        assert_eq!(
            Bounds::of(&pts),
            Some(Bounds {
                x_min_mm: -3.0,
                x_max_mm: 1.0,
                y_min_mm: -2.0,
                y_max_mm: 4.0
            })
        );
    }

    #[test]
    fn cells_are_counted_top_row_first() {
        let geometry = PsdGeometry::default();
        let pts = [
            // Top-left corner cell (exactly on the outer border).
            Vector2::new(-4.5, 4.5),
            // Bottom-right corner cell.
            Vector2::new(4.5, -4.5),
            Vector2::new(4.4, -4.4),
            // Centre: x = 0 is the border between columns 4 and 5 → column 5;
            // y = 0 is the border between rows 4 and 5 → row 5.
            Vector2::new(0.0, 0.0),
            // Off the sensor: bounding box only.
            Vector2::new(6.0, 0.0),
        ];
        let c = Coverage::of(&pts, &geometry, 10);
        assert_eq!(c.cells_per_side, 10);
        assert_eq!(c.cells_covered, 3);
        assert_eq!(c.fraction, 0.03);
        assert_eq!(c.counts[0][0], 1);
        assert_eq!(c.counts[9][9], 2);
        assert_eq!(c.counts[5][5], 1);
        assert_eq!(c.bounds.unwrap().x_max_mm, 6.0);
        let map = c.ascii_map();
        assert_eq!(map.len(), 10);
        assert_eq!(map[0], "#.........");
        assert_eq!(map[5], ".....#....");
        assert_eq!(map[9], ".........#");
    }

    #[test]
    fn empty_and_degenerate_grids() {
        let c = Coverage::of(&[], &PsdGeometry::default(), 0);
        assert_eq!(c.cells_per_side, 1);
        assert_eq!(c.cells_covered, 0);
        assert_eq!(c.fraction, 0.0);
        assert_eq!(c.bounds, None);
        assert_eq!(c.ascii_map(), vec!["."]);
    }
}
