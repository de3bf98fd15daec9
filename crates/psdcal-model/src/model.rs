//! [`Model`]: the sensor model as a chain of stages with one flat, named
//! parameter vector (docs/model.md §8).
//!
//! ```text
//! amplitudes ─[gains]─► measured m ─[s₁]─► … ─[s_K]─► ideal x ─[pinhole]─► ray (a, b)
//! ```
//!
//! The gains stage is optional (present when the model owns the channel
//! gains); the distortion stages `s₁ … s_K` are any [`Stage`]s (PSD radial,
//! lens, a PSD map, …); the pinhole closes every chain. Parameters are named:
//! the flat vector holds each name once, in the canonical order `f, cx, cy,
//! skew, k1, k2, k3, p1, p2, l1, l2`, then the other stages' names in chain
//! order, then `g_x2, g_y1, g_y2`. A stage's block is gathered from the flat
//! vector, so stages that name the same parameter share it.
//!
//! Evaluating the chain (measured → ideal → ray, its Jacobians and its
//! inverse) is in `model/evaluate.rs`.

use std::sync::Arc;

use nalgebra::Vector2;

use crate::params::{Param, SensorModel};
use crate::stage::{ParameterInfo, Stage};
use crate::stages::gains::GAIN_NAMES;
use crate::stages::{Gains, Lens, Pinhole, PsdRadial};
use crate::{ModelError, PsdGeometry};

mod evaluate;
pub use evaluate::ChainJacobian;

/// The chain of stages and its parameter values.
#[derive(Debug, Clone)]
pub struct Model {
    gains: Option<Gains>,
    stages: Arc<[Box<dyn Stage>]>,
    pinhole: Arc<Pinhole>,
    info: Arc<[ParameterInfo]>,
    values: Vec<f64>,
    /// Per distortion stage, the flat index of each of its parameters.
    columns: Arc<[Vec<usize>]>,
    pinhole_columns: [usize; 4],
    gain_columns: Option<[usize; 3]>,
    /// Per distortion stage, its block gathered from `values`.
    blocks: Vec<Vec<f64>>,
}

impl PartialEq for Model {
    fn eq(&self, other: &Self) -> bool {
        self.gains == other.gains
            && self.info == other.info
            && self.values == other.values
            && self.stage_kinds() == other.stage_kinds()
    }
}

/// Canonical position of the standard parameter names.
fn canonical_rank(name: &str) -> Option<usize> {
    Param::ALL.iter().position(|p| p.name() == name)
}

impl Model {
    /// A model from its distortion stages (measured → ideal order) and
    /// parameter values by name (missing names take their neutral value);
    /// with `gains`, the model also owns the channel gains.
    pub fn new(
        stages: Vec<Box<dyn Stage>>,
        gains: Option<Gains>,
        values: &[(&str, f64)],
    ) -> Result<Self, ModelError> {
        let pinhole = Pinhole::new();
        let mut info: Vec<ParameterInfo> = Vec::new();
        let mut add = |p: &ParameterInfo| -> Result<(), ModelError> {
            match info.iter().find(|q| q.name == p.name) {
                Some(q) if q.unit != p.unit => Err(ModelError::InvalidModel {
                    reason: format!(
                        "parameter '{}' is named by two stages with different units ({} and {})",
                        p.name, q.unit, p.unit
                    ),
                }),
                Some(_) => Ok(()),
                None => {
                    info.push(p.clone());
                    Ok(())
                }
            }
        };
        for stage in &stages {
            if stage.kind() == "pinhole" {
                return Err(ModelError::InvalidModel {
                    reason: "the pinhole closes every chain; it is not a distortion stage".into(),
                });
            }
            stage.parameters().iter().try_for_each(&mut add)?;
        }
        pinhole.parameters().iter().try_for_each(&mut add)?;
        if gains.is_some() {
            Gains::parameters().iter().try_for_each(&mut add)?;
        }
        // Canonical names first, then the others in chain order, gains last.
        let chain_order: Vec<String> = info.iter().map(|p| p.name.clone()).collect();
        info.sort_by_key(|p| {
            let gain = GAIN_NAMES.contains(&p.name.as_str());
            let chain = chain_order.iter().position(|n| *n == p.name).unwrap_or(0);
            match (canonical_rank(&p.name), gain) {
                (Some(r), _) => (0, r),
                (None, false) => (1, chain),
                (None, true) => (2, chain),
            }
        });
        let index = |name: &str| info.iter().position(|p| p.name == name).unwrap_or(0);
        let columns: Vec<Vec<usize>> = stages
            .iter()
            .map(|s| s.parameters().iter().map(|p| index(&p.name)).collect())
            .collect();
        let pinhole_columns = [index("f"), index("cx"), index("cy"), index("skew")];
        let gain_columns = gains.as_ref().map(|_| {
            [
                index(GAIN_NAMES[0]),
                index(GAIN_NAMES[1]),
                index(GAIN_NAMES[2]),
            ]
        });
        let mut model = Self {
            values: info.iter().map(|p| p.neutral).collect(),
            blocks: stages
                .iter()
                .map(|s| vec![0.0; s.parameters().len()])
                .collect(),
            gains,
            stages: stages.into(),
            pinhole: Arc::new(pinhole),
            info: info.into(),
            columns: columns.into(),
            pinhole_columns,
            gain_columns,
        };
        for (name, value) in values {
            model.set(name, *value)?;
        }
        model.gather();
        Ok(model)
    }

    /// The standard chain (PSD radial → lens → pinhole) with the values of
    /// `sensor`.
    pub fn standard(sensor: &SensorModel) -> Self {
        let values: Vec<(&str, f64)> = Param::ALL
            .iter()
            .map(|p| (p.name(), sensor.get(*p)))
            .collect();
        let stages: Vec<Box<dyn Stage>> = vec![Box::new(PsdRadial::new()), Box::new(Lens::new())];
        // The standard names always exist: this cannot fail.
        Self::new(stages, None, &values).unwrap_or_else(|_| unreachable!())
    }

    /// The standard chain with the channel gains as its first stage.
    pub fn standard_with_gains(
        sensor: &SensorModel,
        geometry: PsdGeometry,
        gains: &crate::ChannelGains,
    ) -> Self {
        let mut model = Self::standard(sensor).with_stages_and_gains(Some(Gains::new(geometry)));
        for (name, value) in GAIN_NAMES.iter().zip(gains.to_array()) {
            let k = model.index(name).unwrap_or(0);
            model.values[k] = value;
        }
        model
    }

    /// The same chain with (or without) the gains stage, values kept.
    pub fn with_stages_and_gains(&self, gains: Option<Gains>) -> Self {
        let values: Vec<(&str, f64)> = self
            .info
            .iter()
            .zip(&self.values)
            .filter(|(p, _)| gains.is_some() || !GAIN_NAMES.contains(&p.name.as_str()))
            .map(|(p, v)| (p.name.as_str(), *v))
            .collect();
        Self::new(self.stages.to_vec(), gains, &values).unwrap_or_else(|_| unreachable!())
    }

    /// A copy with `stage` inserted before the distortion stage at `position`
    /// (0: first, acting on the measured point); its parameters keep their
    /// neutral values unless set later.
    pub fn with_stage(&self, position: usize, stage: Box<dyn Stage>) -> Result<Self, ModelError> {
        let mut stages = self.stages.to_vec();
        stages.insert(position.min(stages.len()), stage);
        let values: Vec<(&str, f64)> = self
            .info
            .iter()
            .zip(&self.values)
            .map(|(p, v)| (p.name.as_str(), *v))
            .collect();
        Self::new(stages, self.gains.clone(), &values)
    }

    /// The standard values, when every standard name is present (the values
    /// of a chain that has other stages too).
    pub fn sensor_model(&self) -> SensorModel {
        let mut sensor = SensorModel::pinhole(1.0, 0.0, 0.0);
        for p in Param::ALL {
            sensor.set(p, self.get(p.name()).unwrap_or(0.0));
        }
        sensor
    }

    /// Whether the chain is exactly the standard one (PSD radial → lens).
    pub fn is_standard(&self) -> bool {
        self.stage_kinds() == ["psd_radial", "lens"]
    }

    /// The channel gains of the model, when it owns them.
    pub fn gains(&self) -> Option<crate::ChannelGains> {
        self.gain_columns.map(|c| crate::ChannelGains {
            x2: self.values[c[0]],
            y1: self.values[c[1]],
            y2: self.values[c[2]],
        })
    }

    /// The gains stage, when the model owns the gains.
    pub fn gains_stage(&self) -> Option<&Gains> {
        self.gains.as_ref()
    }

    /// Flat indices of `g_x2, g_y1, g_y2`, when the model owns the gains.
    pub fn gain_columns(&self) -> Option<[usize; 3]> {
        self.gain_columns
    }

    /// The distortion stages, measured → ideal.
    pub fn stages(&self) -> &[Box<dyn Stage>] {
        &self.stages
    }

    /// Kinds of the distortion stages, measured → ideal.
    pub fn stage_kinds(&self) -> Vec<&str> {
        self.stages.iter().map(|s| s.kind()).collect()
    }

    /// Flat indices of distortion stage `k`'s parameters.
    pub fn stage_columns(&self, k: usize) -> &[usize] {
        &self.columns[k]
    }

    /// Flat indices of the pinhole's `f, cx, cy, skew`.
    pub fn pinhole_columns(&self) -> [usize; 4] {
        self.pinhole_columns
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether the model has no parameter (never: the pinhole has four).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Every parameter's description, in flat order.
    pub fn parameters(&self) -> &[ParameterInfo] {
        &self.info
    }

    /// Parameter names in flat order.
    pub fn names(&self) -> Vec<&str> {
        self.info.iter().map(|p| p.name.as_str()).collect()
    }

    /// The flat parameter vector.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Flat index of a parameter.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.info.iter().position(|p| p.name == name)
    }

    /// A parameter's value.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.index(name).map(|k| self.values[k])
    }

    /// Sets a parameter by name.
    pub fn set(&mut self, name: &str, value: f64) -> Result<(), ModelError> {
        let k = self.index(name).ok_or_else(|| ModelError::InvalidModel {
            reason: format!(
                "the model has no parameter '{name}' (it has {})",
                self.names().join(", ")
            ),
        })?;
        self.values[k] = value;
        self.gather();
        Ok(())
    }

    /// Replaces the flat vector (same length).
    pub fn set_values(&mut self, values: &[f64]) {
        self.values.copy_from_slice(values);
        self.gather();
    }

    /// A copy with the flat vector changed by `delta` at `columns`.
    pub fn stepped(&self, columns: &[usize], delta: &[f64]) -> Self {
        let mut next = self.clone();
        for (c, d) in columns.iter().zip(delta) {
            next.values[*c] += d;
        }
        next.gather();
        next
    }

    fn gather(&mut self) {
        for (block, cols) in self.blocks.iter_mut().zip(self.columns.iter()) {
            for (b, c) in block.iter_mut().zip(cols) {
                *b = self.values[*c];
            }
        }
    }

    /// Checks every stage's block (finite values, `f > 0`, positive gains).
    pub fn validate(&self) -> Result<(), ModelError> {
        for (stage, block) in self.stages.iter().zip(&self.blocks) {
            stage.validate(block)?;
        }
        self.pinhole.validate(&self.pinhole_block())?;
        if let Some(g) = self.gains() {
            g.validate()?;
        }
        Ok(())
    }

    fn pinhole_block(&self) -> [f64; 4] {
        self.pinhole_columns.map(|c| self.values[c])
    }

    fn pinhole_intrinsics(&self) -> crate::stages::pinhole::PinholeIntrinsics {
        let [f, cx, cy, skew] = self.pinhole_block();
        crate::stages::pinhole::PinholeIntrinsics {
            f,
            c: Vector2::new(cx, cy),
            skew,
        }
    }
}

impl From<&SensorModel> for Model {
    fn from(sensor: &SensorModel) -> Self {
        Model::standard(sensor)
    }
}

impl From<SensorModel> for Model {
    fn from(sensor: SensorModel) -> Self {
        Model::standard(&sensor)
    }
}

impl From<&Model> for Model {
    fn from(model: &Model) -> Self {
        model.clone()
    }
}
