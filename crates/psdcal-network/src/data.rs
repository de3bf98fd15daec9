//! What a network calibration starts from: each sensor's lab calibration
//! (model, the names of its lab-estimated parameters and their covariance:
//! the Gaussian prior), the wand's LEDs in the wand's frame, optionally the
//! static frame's LEDs at known world positions, and what each sensor
//! measured of each LED at each instant.

use nalgebra::{DMatrix, Vector2, Vector3};
use psdcal_model::{Model, PsdGeometry};

use crate::NetworkError;

/// One sensor: its lab model and the prior on its lens parameters.
#[derive(Debug, Clone)]
pub struct NetworkSensor {
    /// Identifier.
    pub id: String,
    /// The lab calibration's model (measured → ray).
    pub model: Model,
    /// Names of the parameters refined under the prior (the lab
    /// calibration's estimated ones; empty: the lens is held).
    pub prior_names: Vec<String>,
    /// Their lab covariance (`prior_names` order).
    pub prior_covariance: DMatrix<f64>,
    /// The PSD's active area.
    pub geometry: PsdGeometry,
}

/// Which LED an observation is of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Led {
    /// The wand's LED `k` (index into [`NetworkData::wand`]).
    Wand(usize),
    /// The static frame's LED `k` (index into [`NetworkData::frame_leds`]).
    Frame(usize),
}

/// One measured impact point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NetworkObservation {
    /// The instant (index into [`NetworkData::frames`]); unused for frame
    /// LEDs.
    pub frame: usize,
    /// The sensor (index into [`NetworkData::sensors`]).
    pub sensor: usize,
    /// The LED.
    pub led: Led,
    /// The measured impact point, mm.
    pub measured: Vector2<f64>,
}

/// Everything a network calibration uses.
#[derive(Debug, Clone)]
pub struct NetworkData {
    /// The sensors (the first one's frame is the world without a static
    /// frame).
    pub sensors: Vec<NetworkSensor>,
    /// The wand's LEDs in its own frame, mm (at least 2).
    pub wand: Vec<Vector3<f64>>,
    /// Names of the wand's LEDs.
    pub wand_names: Vec<String>,
    /// The static frame's LEDs in the world, mm (empty, or at least 3 not
    /// collinear).
    pub frame_leds: Vec<Vector3<f64>>,
    /// Names of the static frame's LEDs.
    pub frame_names: Vec<String>,
    /// Frame (instant) identifiers.
    pub frames: Vec<String>,
    /// The observations, any order.
    pub observations: Vec<NetworkObservation>,
}

impl NetworkData {
    /// Checks sizes, indices and values.
    pub fn validate(&self) -> Result<(), NetworkError> {
        let bad = |m: String| Err(NetworkError::Input(m));
        if self.sensors.len() < 2 {
            return bad(format!(
                "a network needs at least 2 sensors ({} given)",
                self.sensors.len()
            ));
        }
        if self.wand.len() < 2 {
            return NetworkError::no_scale_wand(self.wand.len());
        }
        let longest = self.wand_distances().into_iter().fold(0.0, f64::max);
        if longest.is_nan() || longest <= 0.0 {
            return Err(NetworkError::NoScale(
                "the wand's LEDs are all at one place: give their positions in the wand's frame \
                 (wand.csv, mm)"
                    .into(),
            ));
        }
        if !self.frame_leds.is_empty() && !spans_plane(&self.frame_leds) {
            return bad(format!(
                "the static frame needs at least 3 LEDs not on one line ({} given)",
                self.frame_leds.len()
            ));
        }
        for s in &self.sensors {
            let n = s.prior_names.len();
            if s.prior_covariance.shape() != (n, n) {
                return bad(format!(
                    "sensor '{}': the prior covariance is {}×{} for {n} parameters",
                    s.id,
                    s.prior_covariance.nrows(),
                    s.prior_covariance.ncols()
                ));
            }
            if let Some(name) = s.prior_names.iter().find(|n| s.model.index(n).is_none()) {
                return bad(format!(
                    "sensor '{}': the model has no parameter '{name}'",
                    s.id
                ));
            }
        }
        for o in &self.observations {
            let led_ok = match o.led {
                Led::Wand(k) => k < self.wand.len(),
                Led::Frame(k) => k < self.frame_leds.len(),
            };
            if o.sensor >= self.sensors.len()
                || o.frame >= self.frames.len().max(1)
                || !led_ok
                || !o.measured.iter().all(|v| v.is_finite())
            {
                return bad(format!("an observation is out of range: {o:?}"));
            }
        }
        Ok(())
    }

    /// Distances between every pair of wand LEDs, mm (pairs `(i, j)`,
    /// `i < j`, in order).
    pub fn wand_distances(&self) -> Vec<f64> {
        let mut d = Vec::new();
        for i in 0..self.wand.len() {
            for j in i + 1..self.wand.len() {
                d.push((self.wand[i] - self.wand[j]).norm());
            }
        }
        d
    }

    /// Whether the wand's LEDs lie on one line (its roll is then not
    /// observable).
    pub fn wand_is_collinear(&self) -> bool {
        !spans_plane(&self.wand)
    }
}

impl NetworkError {
    fn no_scale_wand(n: usize) -> Result<(), NetworkError> {
        Err(NetworkError::NoScale(format!(
            "the wand has {n} LED(s); its length (at least 2 LEDs at known distance, wand.csv) \
             gives the network its scale"
        )))
    }
}

/// Whether points span a plane (at least 3, not all on one line), relative
/// to their extent.
pub fn spans_plane(points: &[Vector3<f64>]) -> bool {
    if points.len() < 3 {
        return false;
    }
    let p0 = points[0];
    let far = points
        .iter()
        .max_by(|a, b| (*a - p0).norm().total_cmp(&(*b - p0).norm()))
        .copied()
        .unwrap_or(p0);
    let axis = far - p0;
    let len = axis.norm();
    if len == 0.0 {
        return false;
    }
    let off = points
        .iter()
        .map(|p| axis.cross(&(p - p0)).norm() / len)
        .fold(0.0, f64::max);
    off > 1e-6 * len
}
