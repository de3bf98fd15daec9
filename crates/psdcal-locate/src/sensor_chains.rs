//! The chains a calibrated sensor's answers evaluate, built once per
//! state of the sensor, not once per point.
//!
//! `aoa` needs the standard chain of the sensor's model, the full chain
//! (gains, PSD map) whose flat parameters the covariance is over, and the
//! columns joining them (by parameter name). Building a chain sorts its
//! stages and names its parameters: about 10 times the cost of the angle
//! itself. The sensor's fields are public, so the cache keeps a copy of
//! what it was built from and is rebuilt when any of it changed (compared
//! on every call: a few hundred instructions).

use std::sync::{Arc, RwLock};

use psdcal_model::stages::{with_aspect, Aspect};
use psdcal_model::{
    ChannelGains, Model, Param, ParameterCovariance, PsdGeometry, SensorModel, Stage,
};

use crate::psd_map::SensorPsdMap;
use crate::uncertainty::covariance_columns;

/// What the chains are built from: a calibrated sensor's fields.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SensorState<'a> {
    pub model: &'a SensorModel,
    pub geometry: &'a PsdGeometry,
    pub gains: &'a Option<ChannelGains>,
    pub psd_map: &'a Option<SensorPsdMap>,
    pub covariance: &'a ParameterCovariance,
    pub aspect: &'a Option<f64>,
}

/// What the chains were built from.
#[derive(Debug, Clone, PartialEq)]
struct ChainKey {
    model: SensorModel,
    geometry: PsdGeometry,
    gains: Option<ChannelGains>,
    psd_map: Option<SensorPsdMap>,
    covariance_names: Vec<String>,
    aspect: Option<f64>,
}

/// The chains of one sensor state and their column maps.
#[derive(Debug)]
pub(crate) struct SensorChains {
    key: ChainKey,
    /// `Model::standard` of the sensor's model, with its aspect stage.
    pub standard: Model,
    /// The aspect's column in `standard` and in `chain`, if it has one.
    pub aspect_columns: Option<(usize, usize)>,
    /// The sensor's full chain (gains, PSD map).
    pub chain: Model,
    /// The column in `chain` of each of `Param::ALL` (`None`: not in it).
    pub model_columns: Vec<Option<usize>>,
    /// The gains' columns in `chain`, if it has them.
    pub gain_columns: Option<[usize; 3]>,
    /// The column in `chain` of each of the PSD map's parameters.
    pub map_columns: Vec<Option<usize>>,
    /// The column in `chain` of each covariance name; `None` when a name
    /// is not in the chain (`propagate` then says which).
    pub covariance_columns: Option<Vec<Option<usize>>>,
}

/// A sensor's [`SensorChains`], shared by the threads answering with it.
/// A copy of the sensor starts empty; two sensors compare equal whatever
/// their caches hold.
#[derive(Default)]
pub(crate) struct ChainCache(RwLock<Option<Arc<SensorChains>>>);

impl ChainCache {
    /// The chains of the sensor in `state`; `chain` builds its full chain
    /// when they must be built again.
    pub fn get(&self, state: SensorState<'_>, chain: impl FnOnce() -> Model) -> Arc<SensorChains> {
        let key = key_of(&state);
        let held = self.0.read().map(|held| held.clone()).unwrap_or_default();
        if let Some(chains) = held.filter(|c| c.key == key) {
            return chains;
        }
        let chains = Arc::new(build(&state, chain(), key));
        if let Ok(mut held) = self.0.write() {
            *held = Some(Arc::clone(&chains));
        }
        chains
    }
}

fn key_of(state: &SensorState<'_>) -> ChainKey {
    ChainKey {
        model: *state.model,
        geometry: *state.geometry,
        gains: *state.gains,
        psd_map: state.psd_map.clone(),
        covariance_names: state.covariance.names().to_vec(),
        aspect: *state.aspect,
    }
}

fn build(sensor: &SensorState<'_>, chain: Model, key: ChainKey) -> SensorChains {
    let model_columns = Param::ALL.iter().map(|p| chain.index(p.name())).collect();
    let map_columns = sensor.psd_map.as_ref().map_or_else(Vec::new, |map| {
        let names = map.stage.parameters();
        names.iter().map(|p| chain.index(&p.name)).collect()
    });
    let standard = Model::standard(sensor.model);
    let standard = match sensor.aspect {
        Some(a) => with_aspect_stage(&standard, *a),
        None => standard,
    };
    let aspect_columns = standard.index(Aspect::NAME).zip(chain.index(Aspect::NAME));
    SensorChains {
        standard,
        aspect_columns,
        model_columns,
        gain_columns: chain.gain_columns(),
        map_columns,
        covariance_columns: covariance_columns(sensor.covariance, &chain).ok(),
        chain,
        key,
    }
}

/// `chain` with the aspect stage `a` before its lens stage (after the
/// PSD's radial one, docs/model.md §3.3); `chain` when it cannot take one.
pub(crate) fn with_aspect_stage(chain: &Model, a: f64) -> Model {
    with_aspect(chain, a).unwrap_or_else(|_| chain.clone())
}

impl Clone for ChainCache {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl PartialEq for ChainCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for ChainCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ChainCache")
    }
}
