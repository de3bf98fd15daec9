//! Calibration templates of the tests: LED positions `(X, Y)` in mm on the
//! template plane, and declared collinear groups (indices into the LEDs).

use nalgebra::Vector2;
use psdcal_model::paper_setup::SCATTER14_MM;

/// Six more LEDs that extend `scatter14` to a 20-LED template (still no
/// three collinear), mm.
pub const EXTRA_MM: [(f64, f64); 6] = [
    (-10.0, -150.0),
    (100.0, 95.0),
    (-150.0, 110.0),
    (15.0, 145.0),
    (150.0, -10.0),
    (-95.0, -95.0),
];

/// The first `leds` LEDs of the 20-LED template: `scatter14` followed by
/// [`EXTRA_MM`] (14 gives `scatter14` itself; at most 20).
pub fn scatter(leds: usize) -> Vec<Vector2<f64>> {
    SCATTER14_MM
        .iter()
        .chain(EXTRA_MM.iter())
        .take(leds)
        .map(|&(x, y)| Vector2::new(x, y))
        .collect()
}

/// A 5 × 5 grid (pitch 75 mm, ±150 mm, row by row from (−150, −150)) and its
/// 12 lines: 5 rows, 5 columns, 2 diagonals (for the line-straightness
/// correction).
pub fn grid75() -> (Vec<Vector2<f64>>, Vec<Vec<usize>>) {
    let pts = (0..5)
        .flat_map(|i| {
            (0..5).map(move |j| Vector2::new(-150.0 + 75.0 * j as f64, -150.0 + 75.0 * i as f64))
        })
        .collect();
    let mut lines: Vec<Vec<usize>> = Vec::new();
    for i in 0..5 {
        lines.push((0..5).map(|j| 5 * i + j).collect());
        lines.push((0..5).map(|j| 5 * j + i).collect());
    }
    lines.push((0..5).map(|k| 6 * k).collect());
    lines.push((0..5).map(|k| 4 * (k + 1)).collect());
    (pts, lines)
}
