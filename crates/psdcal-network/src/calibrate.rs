//! The whole network calibration: validate, start, adjust, then each
//! sensor's estimate with its covariance and the diagnostics.

use nalgebra::{DMatrix, SMatrix};
use psdcal_model::Pose;
use psdcal_solver::solver::SolverReport;

use crate::adjust::{adjust, AdjustOptions, DropReason};
use crate::data::NetworkData;
use crate::diagnose::{diagnose, NetworkDiagnostics};
pub use crate::estimate::{Gauge, SensorEstimate};
use crate::start::{start, StartOptions};
use crate::view_graph::TreeEdge;
use crate::NetworkError;

/// Options of a network calibration.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NetworkOptions {
    /// The start.
    pub start: StartOptions,
    /// The adjustment.
    pub adjust: AdjustOptions,
    /// Least frames placed at the start.
    pub min_frames: MinFrames,
}

/// The least number of frames a calibration accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MinFrames(pub usize);

impl Default for MinFrames {
    fn default() -> Self {
        Self(20)
    }
}

/// The calibrated network.
#[derive(Debug, Clone)]
pub struct NetworkResult {
    /// Per sensor, in input order.
    pub sensors: Vec<SensorEstimate>,
    /// What fixes the world.
    pub gauge: Gauge,
    /// Per frame, the wand's `world_from_wand` when used.
    pub wands: Vec<Option<Pose>>,
    /// Frames used.
    pub frames_used: usize,
    /// Frames dropped and why.
    pub dropped: Vec<(usize, DropReason)>,
    /// Static-frame sightings dropped (observation indices).
    pub dropped_statics: Vec<usize>,
    /// Point noise σ, mm.
    pub sigma_mm: f64,
    /// The spanning tree of the start.
    pub tree: Vec<TreeEdge>,
    /// Shared sightings per sensor pair.
    pub shared: Vec<Vec<usize>>,
    /// The last pass's solver report.
    pub report: SolverReport,
    /// Iterations over every pass.
    pub iterations: usize,
    /// Diagnostics.
    pub diagnostics: NetworkDiagnostics,
}

/// Calibrates the network (module documentation).
pub fn calibrate_network(
    data: &NetworkData,
    options: &NetworkOptions,
) -> Result<NetworkResult, NetworkError> {
    data.validate()?;
    let usable = usable_frames(data);
    if usable < options.min_frames.0 {
        return Err(NetworkError::TooFewFrames {
            usable,
            needed: options.min_frames.0,
        });
    }
    let s = start(data, &options.start)?;
    let placed = s.wands.iter().filter(|w| w.is_some()).count();
    if placed < options.min_frames.0 {
        return Err(NetworkError::TooFewFrames {
            usable: placed,
            needed: options.min_frames.0,
        });
    }
    let a = adjust(data, &s.sensors, &s.wands, &options.adjust)?;
    let mut points = vec![0usize; data.sensors.len()];
    let mut residual = vec![0.0; data.sensors.len()];
    let problem = crate::problem::NetworkProblem::new(
        data,
        &a.layout,
        a.by_block.clone(),
        a.statics.clone(),
        a.sigma_mm,
        &a.state.wands,
        &a.state.models,
    )?;
    for (b, obs) in a.by_block.iter().enumerate() {
        for &k in obs {
            let s = data.observations[k].sensor;
            points[s] += 1;
            residual[s] += problem
                .residual_mm(&a.state, Some(b), k)
                .map_or(0.0, |r| r.norm_squared());
        }
    }
    for &k in &a.statics {
        let s = data.observations[k].sensor;
        points[s] += 1;
        residual[s] += problem
            .residual_mm(&a.state, None, k)
            .map_or(0.0, |r| r.norm_squared());
    }
    let sensors = (0..data.sensors.len())
        .map(|k| {
            let pose = a.state.sensors[k];
            let cols = &a.layout.columns[k];
            let n_lens = a.layout.lens[k].len();
            let mut pose_covariance = SMatrix::<f64, 6, 6>::zeros();
            if let Some(c) = a.layout.pose[k] {
                for i in 0..6 {
                    for j in 0..6 {
                        pose_covariance[(i, j)] = a.covariance[(c + i, c + j)];
                    }
                }
            }
            let lens = &a.layout.lens[k];
            let lens_covariance =
                DMatrix::from_fn(n_lens, n_lens, |i, j| a.covariance[(lens[i], lens[j])]);
            let _ = cols;
            let (position_mm, j) = pose.centre_with_jacobian();
            SensorEstimate {
                sensor_from_world: pose,
                pose_covariance,
                position_mm,
                position_covariance: j * pose_covariance * j.transpose(),
                model: a.state.models[k].clone(),
                lens_names: data.sensors[k].prior_names.clone(),
                lens_covariance,
                points: points[k],
                residual_mm2: residual[k],
            }
        })
        .collect::<Vec<_>>();
    let mut wands = vec![None; data.frames.len()];
    for (b, &f) in a.frames.iter().enumerate() {
        wands[f] = Some(a.state.wands[b]);
    }
    let gauge = if data.frame_leds.is_empty() {
        Gauge::FirstSensor
    } else {
        Gauge::StaticFrame
    };
    let diagnostics = diagnose(data, &a, &sensors, &s.shared, gauge);
    Ok(NetworkResult {
        sensors,
        gauge,
        wands,
        frames_used: a.frames.len(),
        dropped: a.dropped,
        dropped_statics: a.dropped_statics,
        sigma_mm: a.sigma_mm,
        tree: s.tree,
        shared: s.shared,
        report: a.report,
        iterations: a.iterations,
        diagnostics,
    })
}

/// Frames in which some wand LED is seen by at least two sensors.
fn usable_frames(data: &NetworkData) -> usize {
    use std::collections::HashMap;
    let mut seen: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for o in &data.observations {
        if let crate::data::Led::Wand(l) = o.led {
            let e = seen.entry((o.frame, l)).or_default();
            if !e.contains(&o.sensor) {
                e.push(o.sensor);
            }
        }
    }
    let mut frames: Vec<usize> = seen
        .iter()
        .filter(|(_, s)| s.len() >= 2)
        .map(|((f, _), _)| *f)
        .collect();
    frames.sort_unstable();
    frames.dedup();
    frames.len()
}
