//! The start of a network calibration, without any guess (docs/network.md):
//!
//! 1. every observation becomes a unit ray through its sensor's lab model;
//! 2. the view graph's maximum spanning tree ([`crate::view_graph`]) orders
//!    the sensors; each tree edge's relative pose comes from the shared rays
//!    ([`crate::essential`]), its scale from the wand: LED pairs of one
//!    frame triangulated by the two sensors, the median of known ÷
//!    triangulated distance;
//! 3. poses are chained from sensor 0 (`c_from_world = c_from_p ∘
//!    p_from_world`);
//! 4. each frame's wand pose: its LEDs triangulated by every sensor that saw
//!    them ([`crate::geometry::meet_rays`]), then the rigid fit of the wand
//!    to them ([`crate::geometry::kabsch`]); frames with too few
//!    triangulated LEDs are not placed;
//! 5. with a static frame, its triangulated LEDs give the rigid map to the
//!    world of the static frame, applied to every pose.

use nalgebra::Vector3;
use psdcal_model::{Model, Pose};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::data::{Led, NetworkData};
use crate::essential::{depths, relative_pose};
use crate::geometry::{kabsch, meet_rays};
use crate::view_graph::{spanning_tree, Sightings, TreeEdge};
use crate::NetworkError;

/// Options of the start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartOptions {
    /// Least shared sightings that place a sensor from another.
    pub min_shared: usize,
    /// Epipolar error (rad) below which a ray pair always agrees (it agrees
    /// up to 4 × the relative pose's median error when that is larger: the
    /// lab models' systematic error).
    pub epipolar_threshold: f64,
    /// RANSAC samples per sensor pair.
    pub ransac_iterations: usize,
    /// Seed of the RANSAC draws.
    pub seed: u64,
}

impl Default for StartOptions {
    fn default() -> Self {
        Self {
            min_shared: 30,
            epipolar_threshold: 5e-3,
            ransac_iterations: 300,
            seed: 1,
        }
    }
}

/// The start: every sensor's pose, every frame's wand pose (or `None`).
#[derive(Debug, Clone)]
pub struct Start {
    /// Each sensor's `sensor_from_world`.
    pub sensors: Vec<Pose>,
    /// Each frame's `world_from_wand`, `None` when it could not be placed.
    pub wands: Vec<Option<Pose>>,
    /// The spanning tree used.
    pub tree: Vec<TreeEdge>,
    /// Shared sightings per sensor pair.
    pub shared: Vec<Vec<usize>>,
}

/// Computes the start (module documentation).
pub fn start(data: &NetworkData, options: &StartOptions) -> Result<Start, NetworkError> {
    let models: Vec<Model> = data.sensors.iter().map(|s| s.model.clone()).collect();
    let sightings = Sightings::of(data, &models);
    let tree = spanning_tree(&sightings.shared, options.min_shared).map_err(|(c, s)| {
        NetworkError::Disconnected {
            sensor: data.sensors[c].id.clone(),
            shared: s,
            needed: options.min_shared,
        }
    })?;
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut sensors = vec![Pose::identity(); data.sensors.len()];
    for edge in &tree {
        let child_from_parent = edge_pose(data, &sightings, edge, options, &mut rng)?;
        sensors[edge.child] = child_from_parent.compose(&sensors[edge.parent]);
    }
    let mut wands = place_wands(data, &sightings, &sensors);
    if !data.frame_leds.is_empty() {
        let new_from_old = frame_alignment(data, &sightings, &sensors)?;
        let old_from_new = new_from_old.inverse();
        for s in &mut sensors {
            *s = s.compose(&old_from_new);
        }
        for w in wands.iter_mut().flatten() {
            *w = new_from_old.compose(w);
        }
    }
    Ok(Start {
        sensors,
        wands,
        tree,
        shared: sightings.shared,
    })
}

/// `child_from_parent`, scaled by the wand.
fn edge_pose(
    data: &NetworkData,
    sightings: &Sightings,
    edge: &TreeEdge,
    options: &StartOptions,
    rng: &mut ChaCha8Rng,
) -> Result<Pose, NetworkError> {
    let name = |k: usize| data.sensors[k].id.as_str();
    let pairs = sightings.pairs(edge.parent, edge.child);
    let rays: Vec<_> = pairs.iter().map(|p| (p.2, p.3)).collect();
    let rel = relative_pose(
        &rays,
        options.epipolar_threshold,
        options.ransac_iterations,
        rng,
    )
    .ok_or_else(|| NetworkError::Numerical {
        stage: "relative pose",
        reason: format!(
            "no essential matrix between sensors '{}' and '{}' from their {} shared sightings",
            name(edge.parent),
            name(edge.child),
            pairs.len()
        ),
    })?;
    let r = rel.j_from_i.rotation();
    let t = rel.j_from_i.t;
    // Triangulated LEDs (parent frame, unit baseline) per frame.
    let mut ratios = Vec::new();
    let mut k = 0;
    while k < pairs.len() {
        let frame = pairs[k].0;
        let mut points: Vec<(usize, Vector3<f64>)> = Vec::new();
        while k < pairs.len() && pairs[k].0 == frame {
            let (_, led, xi, xj) = pairs[k];
            if rel.inliers[k] {
                if let Some((si, sj)) = depths(&r, &t, &xi, &xj) {
                    if si > 0.0 && sj > 0.0 {
                        let c = -(r.transpose() * t);
                        let p = 0.5 * (xi * si + c + r.transpose() * xj * sj);
                        points.push((led, p));
                    }
                }
            }
            k += 1;
        }
        for a in 0..points.len() {
            for b in a + 1..points.len() {
                let known = (data.wand[points[a].0] - data.wand[points[b].0]).norm();
                let seen = (points[a].1 - points[b].1).norm();
                if known > 0.0 && seen > 0.0 {
                    ratios.push(known / seen);
                }
            }
        }
    }
    if ratios.is_empty() {
        return Err(NetworkError::NoScale(format!(
            "sensors '{}' and '{}' never both saw two wand LEDs in one frame, so the wand \
             cannot scale their relative pose; wave the whole wand where both see it",
            name(edge.parent),
            name(edge.child)
        )));
    }
    let scale = median(&mut ratios);
    Ok(Pose::new(rel.j_from_i.rvec, t * scale))
}

/// The median (sorts the slice).
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// A wand LED or static LED triangulated in the world from every sensor
/// that saw it.
fn triangulate(
    sightings: &Sightings,
    sensors: &[Pose],
    seen: &[(usize, usize)],
) -> Option<Vector3<f64>> {
    let rays: Vec<_> = seen
        .iter()
        .map(|&(s, k)| {
            let world_from_sensor = sensors[s].inverse();
            (
                world_from_sensor.t,
                world_from_sensor.rotation() * sightings.rays[k],
            )
        })
        .collect();
    meet_rays(&rays)
}

/// Each frame's wand pose from its triangulated LEDs.
fn place_wands(data: &NetworkData, sightings: &Sightings, sensors: &[Pose]) -> Vec<Option<Pose>> {
    let needed = if data.wand_is_collinear() { 2 } else { 3 };
    let mut points: Vec<Vec<(Vector3<f64>, Vector3<f64>)>> = vec![Vec::new(); data.frames.len()];
    for ((frame, led), seen) in &sightings.by_point {
        let distinct = {
            let mut s: Vec<usize> = seen.iter().map(|x| x.0).collect();
            s.sort_unstable();
            s.dedup();
            s.len()
        };
        if distinct >= 2 {
            if let Some(p) = triangulate(sightings, sensors, seen) {
                points[*frame].push((data.wand[*led], p));
            }
        }
    }
    points
        .iter()
        .map(|pairs| {
            if pairs.len() >= needed {
                kabsch(pairs)
            } else {
                None
            }
        })
        .collect()
}

/// The rigid map from the chained world to the static frame's world.
fn frame_alignment(
    data: &NetworkData,
    sightings: &Sightings,
    sensors: &[Pose],
) -> Result<Pose, NetworkError> {
    let mut pairs = Vec::new();
    let mut unseen = Vec::new();
    for (l, world) in data.frame_leds.iter().enumerate() {
        let seen: Vec<(usize, usize)> = data
            .observations
            .iter()
            .enumerate()
            .filter(|(_, o)| o.led == Led::Frame(l))
            .map(|(k, o)| (o.sensor, k))
            .collect();
        let rays: Vec<_> = seen
            .iter()
            .map(|&(s, k)| {
                let o = &data.observations[k];
                let ab = data.sensors[s].model.ray(&o.measured);
                let w = sensors[s].inverse();
                (
                    w.t,
                    w.rotation() * Vector3::new(ab.x, ab.y, 1.0).normalize(),
                )
            })
            .collect();
        let _ = sightings;
        match meet_rays(&rays) {
            Some(p) => pairs.push((p, *world)),
            None => unseen.push(data.frame_names[l].clone()),
        }
    }
    if pairs.len() < 3 || !crate::data::spans_plane(&pairs.iter().map(|p| p.1).collect::<Vec<_>>())
    {
        return Err(NetworkError::Input(format!(
            "the static frame fixes the world only when at least 3 of its LEDs (not on one line) \
             are each seen by 2 sensors or more; not so for {}: place the frame where more \
             sensors see it, or calibrate without it (the world is then the first sensor's frame)",
            if unseen.is_empty() {
                "its LEDs".to_string()
            } else {
                unseen.join(", ")
            }
        )));
    }
    kabsch(&pairs).ok_or(NetworkError::Numerical {
        stage: "static frame",
        reason: "the frame's LEDs could not be aligned".into(),
    })
}
