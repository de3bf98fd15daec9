//! A sensor's PSD non-linearity map (docs/model.md §8.3), applied to the
//! measured point before the rest of the model: `m' = m + Σ a_k φ_k(m)`,
//! with `∂m'/∂m` (for the point noise and the gains) and `∂m'/∂a` (for the
//! map's own uncertainty). Outside the map's domain (its scan's hull) there
//! is no answer: `outside_valid_region`.

use nalgebra::{Matrix2, Vector2};
use psdcal_model::stages::PsdMap;
use psdcal_model::{Stage, StageJacobian};

/// The map and its coefficients.
#[derive(Debug, Clone)]
pub struct SensorPsdMap {
    /// The stage (basis, frame, hull).
    pub stage: PsdMap,
    /// Its block `(a_x, a_y)`, mm.
    pub block: Vec<f64>,
}

impl PartialEq for SensorPsdMap {
    fn eq(&self, other: &Self) -> bool {
        self.block == other.block && self.stage.configuration() == other.stage.configuration()
    }
}

/// A corrected point with its Jacobians.
#[derive(Debug, Clone)]
pub struct MapCorrection {
    /// `m'`, mm.
    pub point: Vector2<f64>,
    /// `∂m'/∂m`.
    pub wrt_measured: Matrix2<f64>,
    /// `∂m'/∂a` (2 × 2K, column-major as [`StageJacobian`]).
    pub wrt_block: Vec<f64>,
}

impl SensorPsdMap {
    /// Whether the map is known at `m` (inside its hull).
    pub fn contains(&self, m: &Vector2<f64>) -> bool {
        self.stage.contains_input(m)
    }

    /// The corrected point with its Jacobians.
    pub fn correct(&self, m: &Vector2<f64>) -> MapCorrection {
        let mut wrt_measured = Matrix2::identity();
        let mut wrt_block = vec![0.0; 2 * self.block.len()];
        let point = self.stage.apply(
            &self.block,
            m,
            Some(StageJacobian {
                wrt_input: &mut wrt_measured,
                wrt_params: &mut wrt_block,
            }),
        );
        MapCorrection {
            point,
            wrt_measured,
            wrt_block,
        }
    }
}
