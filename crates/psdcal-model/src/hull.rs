//! [`ConvexHull`]: the convex hull of a set of points in the plane, the
//! domain of a stage fitted to scattered data (a PSD map is defined on the
//! hull of its scan, docs/model.md §8.3).
//!
//! Construction: Andrew's monotone chain (sort by `x` then `y`, lower and
//! upper chains, collinear points dropped), `O(n log n)`. Vertices are
//! counter-clockwise. A point `p` is inside when for every edge `a → b`
//!
//! ```text
//! cross(b − a, p − a) ≥ −ε · |b − a|,    ε = 1e-9 mm
//! ```
//!
//! (on the left of every edge, the boundary included with a tolerance of a
//! nanometre).

use nalgebra::Vector2;

use crate::ModelError;

/// Tolerance of the inside test, mm.
pub const HULL_TOLERANCE_MM: f64 = 1e-9;

/// A convex polygon (counter-clockwise vertices, at least three, not all on
/// a line).
#[derive(Debug, Clone, PartialEq)]
pub struct ConvexHull {
    vertices: Vec<Vector2<f64>>,
}

fn cross(o: &Vector2<f64>, a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
}

impl ConvexHull {
    /// The hull of `points` (finite); refused when they span no area.
    pub fn of_points(points: &[Vector2<f64>]) -> Result<Self, ModelError> {
        if points.iter().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
            return Err(ModelError::NonFinite { what: "hull point" });
        }
        let mut p: Vec<Vector2<f64>> = points.to_vec();
        p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        p.dedup();
        if p.len() < 3 {
            return Err(flat(p.len()));
        }
        let mut lower: Vec<Vector2<f64>> = Vec::new();
        for q in &p {
            while lower.len() >= 2
                && cross(&lower[lower.len() - 2], &lower[lower.len() - 1], q) <= 0.0
            {
                lower.pop();
            }
            lower.push(*q);
        }
        let mut upper: Vec<Vector2<f64>> = Vec::new();
        for q in p.iter().rev() {
            while upper.len() >= 2
                && cross(&upper[upper.len() - 2], &upper[upper.len() - 1], q) <= 0.0
            {
                upper.pop();
            }
            upper.push(*q);
        }
        lower.pop();
        upper.pop();
        lower.extend(upper);
        Self::from_vertices(lower)
    }

    /// A hull from its vertices (counter-clockwise, convex); refused
    /// otherwise (a file's hull is checked with this).
    pub fn from_vertices(vertices: Vec<Vector2<f64>>) -> Result<Self, ModelError> {
        let n = vertices.len();
        if n < 3 {
            return Err(flat(n));
        }
        if vertices
            .iter()
            .any(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(ModelError::NonFinite {
                what: "hull vertex",
            });
        }
        for i in 0..n {
            let (a, b, c) = (&vertices[i], &vertices[(i + 1) % n], &vertices[(i + 2) % n]);
            if cross(a, b, c) <= 0.0 {
                return Err(ModelError::InvalidModel {
                    reason: format!(
                        "the hull's vertices {}–{} do not turn counter-clockwise (a hull is \
                         convex, its vertices counter-clockwise)",
                        i,
                        (i + 2) % n
                    ),
                });
            }
        }
        let hull = Self { vertices };
        if hull.area() <= 0.0 {
            return Err(flat(n));
        }
        Ok(hull)
    }

    /// The vertices, counter-clockwise.
    pub fn vertices(&self) -> &[Vector2<f64>] {
        &self.vertices
    }

    /// The enclosed area, mm² (shoelace formula).
    pub fn area(&self) -> f64 {
        let n = self.vertices.len();
        0.5 * (0..n)
            .map(|i| {
                let (a, b) = (&self.vertices[i], &self.vertices[(i + 1) % n]);
                a.x * b.y - b.x * a.y
            })
            .sum::<f64>()
    }

    /// Whether `p` is inside or on the boundary (see the module documentation).
    pub fn contains(&self, p: &Vector2<f64>) -> bool {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return false;
        }
        let n = self.vertices.len();
        (0..n).all(|i| {
            let (a, b) = (&self.vertices[i], &self.vertices[(i + 1) % n]);
            cross(a, b, p) >= -HULL_TOLERANCE_MM * (b - a).norm()
        })
    }

    /// How far the ray `c + t u` (`t ≥ 0`, `u` a unit vector, `c` inside)
    /// runs before it leaves the hull, mm: the smallest
    /// `t = −n·(c − a) / (n·u)` over the edges `a → b` whose outward normal
    /// `n = (b_y − a_y, a_x − b_x)` has `n·u > 0`; 0 when `c` is outside.
    pub fn exit_distance(&self, c: &Vector2<f64>, u: &Vector2<f64>) -> f64 {
        let n = self.vertices.len();
        let mut exit = f64::INFINITY;
        for i in 0..n {
            let (a, b) = (&self.vertices[i], &self.vertices[(i + 1) % n]);
            let normal = Vector2::new(b.y - a.y, a.x - b.x);
            let inside = -normal.dot(&(c - a));
            if inside < 0.0 {
                return 0.0;
            }
            let along = normal.dot(u);
            if along > 0.0 {
                exit = exit.min(inside / along);
            }
        }
        if exit.is_finite() {
            exit
        } else {
            0.0
        }
    }

    /// The smallest box holding the hull: `(min, max)` corners, mm.
    pub fn bounds(&self) -> (Vector2<f64>, Vector2<f64>) {
        let mut lo = self.vertices[0];
        let mut hi = self.vertices[0];
        for v in &self.vertices {
            lo = lo.inf(v);
            hi = hi.sup(v);
        }
        (lo, hi)
    }
}

fn flat(n: usize) -> ModelError {
    ModelError::InvalidModel {
        reason: format!("a hull needs three points not on one line (got {n} distinct)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_grid_is_its_square() {
        let mut pts = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                pts.push(Vector2::new(i as f64 - 2.0, j as f64 - 2.0));
            }
        }
        let hull = ConvexHull::of_points(&pts).unwrap();
        assert_eq!(hull.vertices().len(), 4);
        assert!((hull.area() - 16.0).abs() < 1e-12);
        assert!(hull.contains(&Vector2::new(2.0, 0.3)));
        assert!(hull.contains(&Vector2::new(-2.0, -2.0)));
        assert!(!hull.contains(&Vector2::new(2.0 + 1e-6, 0.0)));
        assert!(!hull.contains(&Vector2::new(f64::NAN, 0.0)));
        assert_eq!(
            hull.bounds(),
            (Vector2::new(-2.0, -2.0), Vector2::new(2.0, 2.0))
        );
    }

    #[test]
    fn collinear_and_clockwise_inputs_are_refused() {
        let line: Vec<_> = (0..5)
            .map(|i| Vector2::new(i as f64, 2.0 * i as f64))
            .collect();
        assert!(ConvexHull::of_points(&line).is_err());
        let cw = vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(0.0, 1.0),
            Vector2::new(1.0, 0.0),
        ];
        assert!(ConvexHull::from_vertices(cw).is_err());
    }
}
