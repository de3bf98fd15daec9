//! calibration.json version 2 (docs/formats.md): the model as an ordered list of
//! stages (measured → ideal), a flat `parameters` map, and `diagnostics`
//! and `provenance`. Read into and written from the same [`Calibration`]
//! record as version 1, so that every command answers the same whichever
//! version it reads.
//!
//! Stages, in order: `gains` (`g_x2`, `g_y1`, `g_y2`; only when gains are
//! part of the model), `psd_radial` (`l1`, `l2`), `aspect` (`a`, only when
//! the model has the y axis's own scale), `lens` (`cx`, `cy`, `k1`,
//! `k2`, `k3`, `p1`, `p2`: lens radial and tangential about the optical
//! centre), `pinhole` (`f`, `skew`). Each is `{"kind", "parameters",
//! "estimated"}`; `parameters` repeats every value by name and must agree.

use std::fmt;

use psdcal_model::{Distortion, Intrinsics, Param, PsdGeometry, SensorModel};
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::ser::Serializer;
use serde::{Deserialize, Serialize};

use super::provenance::{Diagnostic, Provenance};
use super::psd_map_stage::{PsdMapScanRecord, PsdMapStageCovariance, PsdMapStageRecord};
use super::records::{
    Covariance, FitSummary, GainsRecord, ImageFit, SensorSize, Software, StdDevs,
};
use super::region::ValidRegionRecord;
use super::rules::{de_format, de_version};
use super::{AspectRecord, Calibration, GAIN_NAMES};

/// The kinds of stage version 2 knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum StageKind {
    Gains,
    PsdMap,
    PsdRadial,
    Aspect,
    Lens,
    Pinhole,
}

impl StageKind {
    const ORDER: [StageKind; 6] = [
        StageKind::Gains,
        StageKind::PsdMap,
        StageKind::PsdRadial,
        StageKind::Aspect,
        StageKind::Lens,
        StageKind::Pinhole,
    ];

    fn name(self) -> &'static str {
        match self {
            StageKind::Gains => "gains",
            StageKind::PsdMap => "psd_map",
            StageKind::PsdRadial => "psd_radial",
            StageKind::Aspect => "aspect",
            StageKind::Lens => "lens",
            StageKind::Pinhole => "pinhole",
        }
    }

    /// The stage's parameter names, in order.
    fn names(self) -> &'static [&'static str] {
        match self {
            StageKind::Gains => &GAIN_NAMES,
            // Runtime-sized: checked against the stage's configuration.
            StageKind::PsdMap => &[],
            StageKind::PsdRadial => &["l1", "l2"],
            StageKind::Aspect => &["a"],
            StageKind::Lens => &["cx", "cy", "k1", "k2", "k3", "p1", "p2"],
            StageKind::Pinhole => &["f", "skew"],
        }
    }
}

/// Values by name, in file order (a JSON object).
#[derive(Debug, Clone, PartialEq, Default)]
struct NamedValues(Vec<(String, f64)>);

impl NamedValues {
    fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }
}

impl Serialize for NamedValues {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_map(self.0.iter().map(|(k, v)| (k, v)))
    }
}

impl<'de> Deserialize<'de> for NamedValues {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct NamedVisitor;
        impl<'de> Visitor<'de> for NamedVisitor {
            type Value = NamedValues;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an object of parameter values by name")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<NamedValues, A::Error> {
                let mut entries: Vec<(String, f64)> = Vec::new();
                while let Some((name, value)) = map.next_entry::<String, f64>()? {
                    if entries.iter().any(|(n, _)| *n == name) {
                        return Err(de::Error::custom(format!(
                            "parameter '{name}' is given twice; expected each once"
                        )));
                    }
                    entries.push((name, value));
                }
                Ok(NamedValues(entries))
            }
        }
        deserializer.deserialize_map(NamedVisitor)
    }
}

/// One stage of the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Stage {
    kind: StageKind,
    parameters: NamedValues,
    #[serde(default)]
    estimated: Vec<String>,
    /// The structure of a runtime-sized stage (`psd_map`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    configuration: Option<serde_json::Value>,
    /// A fixed stage's own covariance (`psd_map`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    covariance: Option<PsdMapStageCovariance>,
    /// The summary of the scan a `psd_map` stage was fitted to.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    scan: Option<PsdMapScanRecord>,
}

/// The version 2 file, field by field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(super) struct FileV2 {
    #[serde(deserialize_with = "de_format")]
    format: String,
    #[serde(deserialize_with = "de_version")]
    version: u32,
    software: Software,
    sensor: SensorSize,
    parameters: NamedValues,
    stages: Vec<Stage>,
    std: StdDevs,
    covariance: Covariance,
    fit: FitSummary,
    images: Vec<ImageFit>,
    #[serde(default)]
    diagnostics: Vec<Diagnostic>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    valid_region: Option<ValidRegionRecord>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    provenance: Option<Provenance>,
}

impl FileV2 {
    /// The file of a calibration record.
    pub(super) fn from_record(c: &Calibration) -> Self {
        let model = c.to_model();
        let mut values: Vec<(String, f64)> = Param::ALL
            .iter()
            .map(|p| (p.name().to_string(), model.get(*p)))
            .collect();
        let mut estimated: Vec<&str> = c.estimated.iter().map(|p| p.name()).collect();
        if let Some(g) = &c.gains {
            let r = g.to_gains();
            values.extend(
                GAIN_NAMES
                    .iter()
                    .zip([r.x2, r.y1, r.y2])
                    .map(|(n, v)| (n.to_string(), v)),
            );
            if g.estimated {
                estimated.extend(GAIN_NAMES);
            }
        }
        if let Some(aspect) = &c.aspect {
            values.push(("a".to_string(), aspect.a));
            if aspect.estimated {
                estimated.push("a");
            }
        }
        let value = |name: &str| {
            values
                .iter()
                .find(|(n, _)| n == name)
                .map_or(0.0, |(_, v)| *v)
        };
        let stages = StageKind::ORDER
            .into_iter()
            .filter(|k| *k != StageKind::Gains || c.gains.is_some())
            .filter(|k| *k != StageKind::Aspect || c.aspect.is_some())
            .filter_map(|kind| match (&c.psd_map, kind) {
                (None, StageKind::PsdMap) => None,
                (Some(map), StageKind::PsdMap) => Some(Stage {
                    kind,
                    parameters: NamedValues(map.parameters.clone()),
                    estimated: if map.estimated {
                        map.parameters.iter().map(|(n, _)| n.clone()).collect()
                    } else {
                        Vec::new()
                    },
                    configuration: Some(map.configuration.clone()),
                    covariance: Some(map.covariance.clone()),
                    scan: map.scan.clone(),
                }),
                _ => Some(Stage {
                    kind,
                    parameters: NamedValues(
                        kind.names()
                            .iter()
                            .map(|n| (n.to_string(), value(n)))
                            .collect(),
                    ),
                    estimated: kind
                        .names()
                        .iter()
                        .filter(|n| estimated.contains(n))
                        .map(|n| n.to_string())
                        .collect(),
                    configuration: None,
                    covariance: None,
                    scan: None,
                }),
            })
            .collect();
        FileV2 {
            format: c.format.clone(),
            version: c.version,
            software: c.software.clone(),
            sensor: c.sensor,
            parameters: NamedValues(values),
            stages,
            std: c.std.clone(),
            covariance: c.covariance.clone(),
            fit: c.fit.clone(),
            images: c.images.clone(),
            diagnostics: c.diagnostics.clone(),
            valid_region: c.valid_region.clone(),
            provenance: c.provenance.clone(),
        }
    }

    /// The record, after checking that the stages and the flat parameters
    /// describe one model; the message names the field.
    pub(super) fn into_record(self) -> Result<Calibration, String> {
        let mut by_kind: Vec<(StageKind, &Stage)> = Vec::new();
        for (i, stage) in self.stages.iter().enumerate() {
            if by_kind.iter().any(|(k, _)| *k == stage.kind) {
                return Err(format!(
                    "stages[{i}]: a second '{}' stage; expected each kind once",
                    stage.kind.name()
                ));
            }
            check_stage(i, stage)?;
            by_kind.push((stage.kind, stage));
        }
        let order: Vec<usize> = by_kind
            .iter()
            .map(|(k, _)| StageKind::ORDER.iter().position(|o| o == k).unwrap_or(0))
            .collect();
        if order.windows(2).any(|w| w[0] > w[1]) {
            return Err(
                "stages are out of order; expected gains, psd_map, psd_radial, lens, pinhole \
                 (measured → ideal)"
                    .to_string(),
            );
        }
        for kind in [StageKind::PsdRadial, StageKind::Lens, StageKind::Pinhole] {
            if !by_kind.iter().any(|(k, _)| *k == kind) {
                return Err(format!("stages: no '{}' stage; expected one", kind.name()));
            }
        }
        let stage_value = |name: &str| {
            by_kind
                .iter()
                .filter(|(k, _)| *k != StageKind::PsdMap)
                .find_map(|(_, s)| s.parameters.get(name))
                .unwrap_or(0.0)
        };
        let psd_map = match by_kind.iter().find(|(k, _)| *k == StageKind::PsdMap) {
            None => None,
            Some((_, s)) => {
                let (Some(configuration), Some(covariance)) = (&s.configuration, &s.covariance)
                else {
                    return Err(
                        "the psd_map stage needs its 'configuration' and 'covariance'".to_string(),
                    );
                };
                let parameters = s.parameters.0.clone();
                let mut listed: Vec<&str> = s.estimated.iter().map(String::as_str).collect();
                let mut names: Vec<&str> = parameters.iter().map(|(n, _)| n.as_str()).collect();
                listed.sort_unstable();
                names.sort_unstable();
                if !listed.is_empty() && listed != names {
                    return Err(
                        "the psd_map stage's 'estimated' must list none of its parameters (held \
                         fixed) or all of them (refined)"
                            .into(),
                    );
                }
                let map = PsdMapStageRecord {
                    configuration: configuration.clone(),
                    parameters,
                    covariance: covariance.clone(),
                    estimated: !s.estimated.is_empty(),
                    scan: s.scan.clone(),
                };
                if let Some(scan) = &map.scan {
                    scan.check()?;
                }
                map.to_stage(self.covariance.parameters.len())?;
                Some(map)
            }
        };
        for (name, value) in &self.parameters.0 {
            let in_stage = by_kind
                .iter()
                .filter(|(k, _)| *k != StageKind::PsdMap)
                .find_map(|(_, s)| s.parameters.get(name));
            match in_stage {
                Some(v) if v == *value => {}
                Some(v) => {
                    return Err(format!(
                        "parameters.{name} is {value} but its stage says {v}; expected the same \
                         value"
                    ))
                }
                None => return Err(format!("parameters.{name}: no stage has this parameter")),
            }
        }
        let model = SensorModel {
            intrinsics: Intrinsics {
                f: stage_value("f"),
                cx: stage_value("cx"),
                cy: stage_value("cy"),
                skew: stage_value("skew"),
            },
            distortion: Distortion {
                k1: stage_value("k1"),
                k2: stage_value("k2"),
                k3: stage_value("k3"),
                p1: stage_value("p1"),
                p2: stage_value("p2"),
                l1: stage_value("l1"),
                l2: stage_value("l2"),
            },
        };
        let estimated_names: Vec<&str> = by_kind
            .iter()
            .flat_map(|(_, s)| s.estimated.iter().map(String::as_str))
            .collect();
        let gains = by_kind
            .iter()
            .find(|(k, _)| *k == StageKind::Gains)
            .map(|(_, s)| GainsRecord {
                x1: 1.0,
                x2: stage_value("g_x2"),
                y1: stage_value("g_y1"),
                y2: stage_value("g_y2"),
                estimated: !s.estimated.is_empty(),
            });
        let mut record = Calibration::from_model(
            &model,
            &PsdGeometry {
                lx: self.sensor.lx_mm,
                ly: self.sensor.ly_mm,
            },
        );
        record.format = self.format;
        record.version = self.version;
        record.software = self.software;
        record.set_estimated(
            &Param::ALL
                .into_iter()
                .filter(|p| estimated_names.contains(&p.name()))
                .collect::<Vec<_>>(),
        );
        record.gains = gains;
        record.std = self.std;
        record.covariance = self.covariance;
        record.fit = self.fit;
        record.images = self.images;
        record.diagnostics = self.diagnostics;
        record.provenance = self.provenance;
        record.valid_region = self.valid_region;
        record.psd_map = psd_map;
        record.aspect = by_kind
            .iter()
            .find(|(k, _)| *k == StageKind::Aspect)
            .map(|(_, s)| AspectRecord {
                a: stage_value("a"),
                estimated: !s.estimated.is_empty(),
            });
        if record.aspect.is_some_and(|a| a.a <= -1.0) {
            return Err(
                "the aspect stage's a must be above -1 (the y scale 1 + a is positive)".into(),
            );
        }
        Ok(record)
    }
}

/// A stage has exactly its parameters, and estimates only its own (the
/// gains all or none).
fn check_stage(i: usize, stage: &Stage) -> Result<(), String> {
    if stage.kind == StageKind::PsdMap {
        // Its names come from its configuration (PsdMapStageRecord::to_stage).
        return Ok(());
    }
    let names = stage.kind.names();
    let kind = stage.kind.name();
    if stage.scan.is_some() {
        return Err(format!(
            "stages[{i}]: 'scan' belongs to a psd_map stage, not to a '{kind}' stage"
        ));
    }
    for (name, _) in &stage.parameters.0 {
        if !names.contains(&name.as_str()) {
            return Err(format!(
                "stages[{i}].parameters: '{name}' is not a parameter of a '{kind}' stage; \
                 expected {}",
                names.join(", ")
            ));
        }
    }
    if let Some(missing) = names.iter().find(|n| stage.parameters.get(n).is_none()) {
        return Err(format!(
            "stages[{i}].parameters: '{missing}' is missing; a '{kind}' stage has {}",
            names.join(", ")
        ));
    }
    for name in &stage.estimated {
        if !names.contains(&name.as_str()) {
            return Err(format!(
                "stages[{i}].estimated: '{name}' is not a parameter of a '{kind}' stage"
            ));
        }
    }
    if stage.kind == StageKind::Gains && !stage.estimated.is_empty() && stage.estimated.len() != 3 {
        return Err(format!(
            "stages[{i}].estimated: the gains are estimated together; expected all of g_x2, \
             g_y1, g_y2 or none"
        ));
    }
    Ok(())
}
