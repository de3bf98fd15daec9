//! A rig: calibrated sensors with known poses in a world frame, and the
//! position of an emitter seen by two or more of them ([`mod@crate::triangulate`]).
//!
//! Each sensor `i` has `world_from_sensor_i` (CONVENTIONS.md: `P_w = R P_s +
//! t`, mm). For an emitter, each observing sensor gives its angle of arrival
//! and the covariance `C_i = Σ_ab,cal + Σ_ab,meas` of its ray
//! ([`crate::calibrated_sensor`]); the rays are intersected in the world frame with
//! covariance `Σ_P = Σ (∂P/∂z_i) C_i (∂P/∂z_i)ᵀ`, reported whole and split
//! into the calibrations' and the measurements' parts.
//!
//! *Shared views.* Two sensors share a view when some point in front of both
//! falls on both active areas. A pair is checked when first asked (and the
//! answer kept), so building a rig and locating emitters take time linear in
//! the sensors and the observations, not in the pairs; a pair is checked by
//! sampling:
//! rays through a 17 × 17 grid over each sensor's active area, points along
//! them from 10 mm to 1 km (40 logarithmic steps), projected into the other
//! sensor. Both directions use each sensor's whole model
//! ([`CalibratedSensor::chain`]: its PSD map first, when it has one): a
//! measured point's ray is `chain.ray(m)` and is used only where the sensor
//! answers (inside its valid region and its map's hull); a point's measured
//! point is the chain's inverse of its ideal point. An emitter whose observing sensors include no sharing pair is
//! answered only if the triangulated point lies in front of all of them and
//! projects onto each of their active areas; otherwise it fails with
//! [`LocateError::NoSharedView`].

use std::collections::HashMap;
use std::sync::Mutex;

use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use psdcal_model::psd::is_on_active_area;
use psdcal_model::{Model, Pose, PsdGeometry};

use crate::calibrated_sensor::{AoaEstimate, CalibratedSensor, LocateOptions, Measurement};
use crate::caution::Caution;
use crate::error::{exceeds, LocateError};
use crate::triangulate::{triangulate, Triangulation, WorldRay};

/// Grid points per side over the active area in the shared-view check.
const VIEW_GRID: usize = 17;
/// Distances sampled along each ray in the shared-view check.
const VIEW_DISTANCES: usize = 40;
/// Relative margin beyond the active area accepted when checking that a
/// triangulated point is in a sensor's view.
const VIEW_MARGIN: f64 = 0.1;

/// One sensor of a rig.
#[derive(Debug, Clone, PartialEq)]
pub struct RigSensor {
    /// Identifier, unique in the rig.
    pub id: String,
    /// The calibrated sensor.
    pub sensor: CalibratedSensor,
    /// Its pose in the world frame.
    pub world_from_sensor: Pose,
}

/// Calibrated sensors with known poses.
#[derive(Debug)]
pub struct Rig {
    sensors: Vec<RigSensor>,
    ids: HashMap<String, usize>,
    /// Each sensor's whole model ([`CalibratedSensor::chain`]).
    chains: Vec<Model>,
    /// Pairs `(i, j)`, `i < j`, checked so far, and whether they share a view.
    shared: Mutex<HashMap<(usize, usize), bool>>,
}

impl Clone for Rig {
    fn clone(&self) -> Self {
        Self {
            sensors: self.sensors.clone(),
            ids: self.ids.clone(),
            chains: self.chains.clone(),
            shared: Mutex::new(self.shared_views().clone()),
        }
    }
}

impl PartialEq for Rig {
    fn eq(&self, other: &Self) -> bool {
        self.sensors == other.sensors
    }
}

/// An emitter located by a rig.
#[derive(Debug, Clone, PartialEq)]
pub struct RigLocation {
    /// Indices of the observing sensors, in the order given.
    pub sensors: Vec<usize>,
    /// Each observing sensor's angle of arrival.
    pub aoa: Vec<AoaEstimate>,
    /// The intersection (its covariance is the total).
    pub triangulation: Triangulation,
    /// Covariance from the calibrations only, world frame, mm².
    pub covariance_calibration: Matrix3<f64>,
    /// Covariance from the point noise only, mm².
    pub covariance_measurement: Matrix3<f64>,
    /// Reasons for care: nearly parallel rays, points off an active area.
    pub cautions: Vec<Caution>,
}

impl Rig {
    /// A rig; identifiers must be unique and poses finite. Which pairs share
    /// a view is found when asked ([`Rig::shares_view`]).
    pub fn new(sensors: Vec<RigSensor>) -> Result<Self, LocateError> {
        let mut ids = HashMap::with_capacity(sensors.len());
        for (i, s) in sensors.iter().enumerate() {
            if ids.insert(s.id.clone(), i).is_some() {
                return Err(LocateError::InvalidInput {
                    what: "rig",
                    reason: format!("sensor id '{}' appears twice; expected unique ids", s.id),
                });
            }
            let pose = &s.world_from_sensor;
            if !pose.rvec.iter().chain(pose.t.iter()).all(|v| v.is_finite()) {
                return Err(LocateError::NonFinite {
                    what: "sensor pose",
                });
            }
            s.sensor.model.validate()?;
        }
        let chains = sensors.iter().map(|s| s.sensor.chain()).collect();
        Ok(Self {
            sensors,
            ids,
            chains,
            shared: Mutex::new(HashMap::new()),
        })
    }

    /// The pairs checked so far (a poisoned lock only means another thread
    /// panicked mid-insert: the map is still valid).
    fn shared_views(&self) -> std::sync::MutexGuard<'_, HashMap<(usize, usize), bool>> {
        self.shared.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The sensors.
    pub fn sensors(&self) -> &[RigSensor] {
        &self.sensors
    }

    /// Index of the sensor called `id`.
    pub fn index_of(&self, id: &str) -> Option<usize> {
        self.ids.get(id).copied()
    }

    /// Whether sensors `i` and `j` share a view (false for `i == j` and
    /// unknown indices); checked on first use, then remembered.
    pub fn shares_view(&self, i: usize, j: usize) -> bool {
        let n = self.sensors.len();
        if i == j || i >= n || j >= n {
            return false;
        }
        let key = (i.min(j), i.max(j));
        if let Some(&known) = self.shared_views().get(&key) {
            return known;
        }
        let a = (&self.sensors[key.0], &self.chains[key.0]);
        let b = (&self.sensors[key.1], &self.chains[key.1]);
        let shared = sees_into(a, b) || sees_into(b, a);
        self.shared_views().insert(key, shared);
        shared
    }

    /// Every pair `(i, j)`, `i < j`, that shares a view (checks all pairs:
    /// quadratic in the sensors; [`Rig::shares_view`] checks one).
    pub fn view_pairs(&self) -> Vec<(usize, usize)> {
        let n = self.sensors.len();
        (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .filter(|&(i, j)| self.shares_view(i, j))
            .collect()
    }

    /// The position of an emitter from the measurements of the sensors that
    /// saw it (`(sensor index, measurement)`, each sensor at most once).
    ///
    /// ```
    /// use nalgebra::{Vector2, Vector3};
    /// use psdcal_locate::{measured_from_ray, CalibratedSensor, LocateOptions, Measurement, Rig, RigSensor};
    /// use psdcal_model::{Pose, PsdGeometry, SensorModel};
    ///
    /// let model = SensorModel::paper_lens2();
    /// let rig = Rig::new(
    ///     [-600.0, 600.0]
    ///         .iter()
    ///         .enumerate()
    ///         .map(|(k, &x)| RigSensor {
    ///             id: format!("s{k}"),
    ///             sensor: CalibratedSensor::new(model, PsdGeometry::default()),
    ///             world_from_sensor: Pose::new(Vector3::zeros(), Vector3::new(x, 0.0, 0.0)),
    ///         })
    ///         .collect(),
    /// )
    /// .unwrap();
    /// let emitter = Vector3::new(100.0, -50.0, 2500.0);
    /// let seen: Vec<(usize, Measurement)> = rig
    ///     .sensors()
    ///     .iter()
    ///     .enumerate()
    ///     .map(|(k, s)| {
    ///         let p = s.world_from_sensor.inverse().transform(&emitter);
    ///         let m = measured_from_ray(&psdcal_model::Model::standard(&model), &Vector2::new(p.x / p.z, p.y / p.z)).unwrap();
    ///         (k, Measurement::Point(m))
    ///     })
    ///     .collect();
    /// let at = rig.locate(&seen, &LocateOptions::default()).unwrap();
    /// assert!((at.triangulation.position - emitter).norm() < 1e-9);
    /// ```
    pub fn locate(
        &self,
        observations: &[(usize, Measurement)],
        options: &LocateOptions,
    ) -> Result<RigLocation, LocateError> {
        options.check()?;
        let mut sensors = Vec::with_capacity(observations.len());
        let mut aoa = Vec::with_capacity(observations.len());
        let mut rays = Vec::with_capacity(observations.len());
        for (k, measurement) in observations {
            let rig_sensor = self
                .sensors
                .get(*k)
                .ok_or_else(|| LocateError::UnknownSensor {
                    sensor: format!("#{k}"),
                })?;
            if sensors.contains(k) {
                return Err(LocateError::InvalidInput {
                    what: "observations",
                    reason: format!(
                        "sensor '{}' observes the emitter twice; expected one measurement per \
                         sensor",
                        rig_sensor.id
                    ),
                });
            }
            let estimate = rig_sensor.sensor.aoa(measurement, options)?;
            rays.push(WorldRay {
                sensor: rig_sensor.id.clone(),
                world_from_sensor: rig_sensor.world_from_sensor,
                ray_ab: estimate.aoa.ray_ab,
                covariance_ab: estimate.ray_covariance(),
            });
            sensors.push(*k);
            aoa.push(estimate);
        }
        if rays.len() < 2 {
            return Err(LocateError::TooFewRays { found: rays.len() });
        }
        let any_shared = sensors
            .iter()
            .enumerate()
            .any(|(a, &i)| sensors[a + 1..].iter().any(|&j| self.shares_view(i, j)));
        let no_view = || LocateError::NoSharedView {
            sensors: sensors
                .iter()
                .map(|&k| self.sensors[k].id.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        };
        let triangulation = match triangulate(&rays, options) {
            Ok(t) => t,
            Err(_) if !any_shared => return Err(no_view()),
            Err(e) => return Err(e),
        };
        if !any_shared
            && !sensors.iter().all(|&k| {
                in_view(
                    (&self.sensors[k], &self.chains[k]),
                    &triangulation.position,
                    VIEW_MARGIN,
                )
            })
        {
            return Err(no_view());
        }
        let cal: Vec<Matrix2<f64>> = aoa.iter().map(|e| e.ray_covariance_calibration).collect();
        let meas: Vec<Matrix2<f64>> = aoa.iter().map(|e| e.ray_covariance_measurement).collect();
        let mut cautions: Vec<Caution> = aoa.iter().flat_map(AoaEstimate::cautions).collect();
        cautions.extend(triangulation.cautions.iter().copied());
        Ok(RigLocation {
            covariance_calibration: triangulation.covariance_from(&cal),
            covariance_measurement: triangulation.covariance_from(&meas),
            sensors,
            aoa,
            triangulation,
            cautions,
        })
    }
}

/// A rig sensor with its whole model.
type Viewer<'a> = (&'a RigSensor, &'a Model);

/// Whether a world point is in front of a sensor and projects, through the
/// sensor's whole model, onto its active area enlarged by `margin`
/// (relative).
fn in_view(sensor: Viewer, p_world: &Vector3<f64>, margin: f64) -> bool {
    let pose = &sensor.0.world_from_sensor;
    in_view_of(
        sensor,
        &pose.rotation().transpose(),
        &pose.t,
        p_world,
        margin,
    )
}

/// [`in_view`] with the sensor's rotation `R` (world from sensor) given as
/// `Rᵀ` and its origin `t`. Without a margin the measured point must also
/// be one the sensor answers (its valid region, its map's hull).
fn in_view_of(
    (sensor, chain): Viewer,
    r_transposed: &Matrix3<f64>,
    origin: &Vector3<f64>,
    p_world: &Vector3<f64>,
    margin: f64,
) -> bool {
    let p = r_transposed * (p_world - origin);
    if !exceeds(p.z, 0.0) {
        return false;
    }
    let ideal = chain.ideal_of_ray(&Vector2::new(p.x / p.z, p.y / p.z));
    let Ok(m) = chain.measured_from_ideal(&ideal) else {
        return false;
    };
    let g = &sensor.sensor.geometry;
    let enlarged = PsdGeometry {
        lx: g.lx * (1.0 + margin),
        ly: g.ly * (1.0 + margin),
    };
    is_on_active_area(&enlarged, &m) && (margin > 0.0 || answers(sensor, chain, &m))
}

/// Whether the sensor answers at measured point `m`: inside its valid
/// region and every stage's domain (its map's hull).
fn answers(sensor: &RigSensor, chain: &Model, m: &Vector2<f64>) -> bool {
    sensor.sensor.check_valid_region(m).is_ok() && chain.in_domain(m)
}

/// Whether some ray of `from`'s active area (where it answers) has a point
/// (10 mm – 1 km away) in `to`'s view.
fn sees_into(from: Viewer, to: Viewer) -> bool {
    let (sensor, chain) = from;
    let g = &sensor.sensor.geometry;
    let rotation = sensor.world_from_sensor.rotation();
    let to_rt = to.0.world_from_sensor.rotation().transpose();
    let last = (VIEW_GRID - 1) as f64;
    for iy in 0..VIEW_GRID {
        for ix in 0..VIEW_GRID {
            let m = Vector2::new(
                g.lx * (ix as f64 / last - 0.5),
                g.ly * (iy as f64 / last - 0.5),
            );
            if !answers(sensor, chain, &m) {
                continue;
            }
            let ab = chain.ray(&m);
            if !(ab.x.is_finite() && ab.y.is_finite()) {
                continue;
            }
            let d = rotation * Vector3::new(ab.x, ab.y, 1.0).normalize();
            for k in 0..VIEW_DISTANCES {
                let range = 10.0 * 1e5f64.powf(k as f64 / (VIEW_DISTANCES - 1) as f64);
                let p = sensor.world_from_sensor.t + d * range;
                if in_view_of(to, &to_rt, &to.0.world_from_sensor.t, &p, 0.0) {
                    return true;
                }
            }
        }
    }
    false
}
