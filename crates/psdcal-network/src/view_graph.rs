//! The sensors' view graph: which sensors saw the same wand LED at the same
//! instant (a *shared sighting*), how often, and the maximum spanning tree
//! over those counts along which relative poses are chained (Prim's
//! algorithm from the first sensor: the tree keeps, for every sensor, its
//! strongest link to the sensors already placed).

use std::collections::HashMap;

use nalgebra::Vector3;

use crate::data::{Led, NetworkData};

/// One sighting: `(frame, wand LED)` and the `(sensor, observation)`
/// pairs that saw it.
pub type Sighting = ((usize, usize), Vec<(usize, usize)>);

/// Observations grouped by sighting: per (frame, wand LED), the sensors that
/// saw it and their unit rays.
#[derive(Debug, Clone)]
pub struct Sightings {
    /// `(frame, wand LED)` → `[(sensor, observation index)]`.
    pub by_point: Vec<Sighting>,
    /// Unit ray (sensor frame) of every observation, by the sensor's lab
    /// model.
    pub rays: Vec<Vector3<f64>>,
    /// `shared[i][j]`: sightings sensors `i` and `j` share.
    pub shared: Vec<Vec<usize>>,
}

impl Sightings {
    /// Groups the wand observations of `data` (rays by `models`).
    pub fn of(data: &NetworkData, models: &[psdcal_model::Model]) -> Self {
        let rays = data
            .observations
            .iter()
            .map(|o| {
                let ab = models[o.sensor].ray(&o.measured);
                Vector3::new(ab.x, ab.y, 1.0).normalize()
            })
            .collect();
        let mut index: HashMap<(usize, usize), usize> = HashMap::new();
        let mut by_point: Vec<Sighting> = Vec::new();
        for (k, o) in data.observations.iter().enumerate() {
            if let Led::Wand(l) = o.led {
                let key = (o.frame, l);
                let slot = *index.entry(key).or_insert_with(|| {
                    by_point.push((key, Vec::new()));
                    by_point.len() - 1
                });
                by_point[slot].1.push((o.sensor, k));
            }
        }
        by_point.sort_by_key(|(key, _)| *key);
        let n = data.sensors.len();
        let mut shared = vec![vec![0usize; n]; n];
        for (_, seen) in &by_point {
            for (a, (si, _)) in seen.iter().enumerate() {
                for (sj, _) in &seen[a + 1..] {
                    if si != sj {
                        shared[*si][*sj] += 1;
                        shared[*sj][*si] += 1;
                    }
                }
            }
        }
        Self {
            by_point,
            rays,
            shared,
        }
    }

    /// The ray pairs `(x_i, x_j)` of the sightings sensors `i` and `j`
    /// share, with their frame and LED.
    pub fn pairs(&self, i: usize, j: usize) -> Vec<(usize, usize, Vector3<f64>, Vector3<f64>)> {
        let mut out = Vec::new();
        for ((frame, led), seen) in &self.by_point {
            let a = seen.iter().find(|(s, _)| *s == i);
            let b = seen.iter().find(|(s, _)| *s == j);
            if let (Some((_, ka)), Some((_, kb))) = (a, b) {
                out.push((*frame, *led, self.rays[*ka], self.rays[*kb]));
            }
        }
        out
    }
}

/// One edge of the spanning tree: `child` is placed from `parent`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TreeEdge {
    /// The sensor already placed.
    pub parent: usize,
    /// The sensor placed through it.
    pub child: usize,
    /// Their shared sightings.
    pub shared: usize,
}

/// The maximum spanning tree from sensor 0 over edges with at least
/// `needed` shared sightings, in placing order; `Err(sensor, best)` names
/// the first sensor that cannot be reached and its best count to a placed
/// sensor.
pub fn spanning_tree(
    shared: &[Vec<usize>],
    needed: usize,
) -> Result<Vec<TreeEdge>, (usize, usize)> {
    let n = shared.len();
    let mut placed = vec![false; n];
    placed[0] = true;
    let mut edges = Vec::with_capacity(n.saturating_sub(1));
    while edges.len() + 1 < n {
        let mut best: Option<TreeEdge> = None;
        for p in (0..n).filter(|&p| placed[p]) {
            for c in (0..n).filter(|&c| !placed[c]) {
                let s = shared[p][c];
                if s >= needed && best.is_none_or(|b| s > b.shared) {
                    best = Some(TreeEdge {
                        parent: p,
                        child: c,
                        shared: s,
                    });
                }
            }
        }
        match best {
            Some(e) => {
                placed[e.child] = true;
                edges.push(e);
            }
            None => {
                let (c, s) = (0..n)
                    .filter(|&c| !placed[c])
                    .map(|c| {
                        let s = (0..n).filter(|&p| placed[p]).map(|p| shared[p][c]).max();
                        (c, s.unwrap_or(0))
                    })
                    .min_by_key(|(_, s)| *s)
                    .unwrap_or((0, 0));
                return Err((c, s));
            }
        }
    }
    Ok(edges)
}
