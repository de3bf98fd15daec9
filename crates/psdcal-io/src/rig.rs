//! rig.json: calibrated sensors with known poses in a world frame, for
//! locating emitters by intersecting the rays of several sensors
//! (docs/positioning.md, "Rig files").
//!
//! ```text
//! { "format": "psdcal-rig", "version": 1,
//!   "sensors": [
//!     { "id": "north", "calibration": "north.json",
//!       "world_from_sensor": { "rvec": [0.0, 0.0, 0.0], "t_mm": [0.0, 0.0, 2500.0] } },
//!     { "id": "east", "calibration": "cal/east.json",
//!       "sensor_from_world": { "rvec": [0.0, 0.5, 0.0], "t_mm": [-1500.0, 0.0, 300.0] } } ] }
//! ```
//!
//! - `format`: always `"psdcal-rig"`; `version`: integer, at most
//!   [`RIG_VERSION`] (a newer file is refused as such).
//! - `sensors`: at least two, each with a unique `id` (text or integer), the
//!   path of its `calibration` (calibration.json; relative paths are taken
//!   from the rig file's folder) and its pose, given as exactly one of
//!   `world_from_sensor` (`P_world = R P_sensor + t`) or `sensor_from_world`
//!   (its inverse): `rvec` a Rodrigues vector in radians, `t_mm` a
//!   translation in mm. The sensor frame is CONVENTIONS.md's: origin at the
//!   PSD's electrical centre, `z` along the optical axis towards the scene.
//!
//! Unknown fields are ignored (later versions may add some). Every error
//! names the file and the field (`sensors[1].world_from_sensor.t_mm`) and
//! says what was expected; JSON syntax errors give line and column.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use psdcal_model::Pose;
use serde_json::{Map, Value};

use crate::error::IoError;
use crate::limits::ReadLimits;

/// The `format` name of rig.json.
pub const RIG_FORMAT: &str = "psdcal-rig";
/// The newest rig.json version this crate reads.
pub const RIG_VERSION: u32 = 1;

/// How a sensor's pose was written in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoseFrame {
    /// As `world_from_sensor`.
    WorldFromSensor,
    /// As `sensor_from_world` (inverted on reading).
    SensorFromWorld,
}

impl PoseFrame {
    /// The field name.
    pub fn field(self) -> &'static str {
        match self {
            PoseFrame::WorldFromSensor => "world_from_sensor",
            PoseFrame::SensorFromWorld => "sensor_from_world",
        }
    }
}

/// One sensor of a rig file.
#[derive(Debug, Clone, PartialEq)]
pub struct RigSensorRecord {
    /// Identifier, unique in the rig.
    pub id: String,
    /// The calibration path as written.
    pub calibration: String,
    /// The calibration path resolved against the rig file's folder.
    pub calibration_path: PathBuf,
    /// The sensor's pose in the world (inverted if written as
    /// `sensor_from_world`).
    pub world_from_sensor: Pose,
    /// How the pose was written.
    pub given_as: PoseFrame,
}

/// A rig file.
#[derive(Debug, Clone, PartialEq)]
pub struct RigFile {
    /// File name, for messages.
    pub source: String,
    /// Format version.
    pub version: u32,
    /// The sensors, in file order.
    pub sensors: Vec<RigSensorRecord>,
}

/// Reads and validates rig.json.
pub fn read_rig(path: impl AsRef<Path>) -> Result<RigFile, IoError> {
    RigFile::read(path)
}

/// [`read_rig`] within `limits` (docs/formats.md, "Limits").
pub fn read_rig_with(path: impl AsRef<Path>, limits: ReadLimits) -> Result<RigFile, IoError> {
    RigFile::read_with(path, limits)
}

impl RigFile {
    /// Reads and validates rig.json; calibration paths are resolved against
    /// its folder.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, IoError> {
        Self::read_with(path, ReadLimits::default())
    }

    /// [`Self::read`] within `limits` (docs/formats.md, "Limits").
    pub fn read_with(path: impl AsRef<Path>, limits: ReadLimits) -> Result<Self, IoError> {
        let path = path.as_ref();
        let source = path.display().to_string();
        let bytes = crate::limits::read_bounded(path, limits)?;
        let text = std::str::from_utf8(&bytes).map_err(|e| IoError::Encoding {
            at: crate::Location::file(&source),
            message: format!(
                "the byte at offset {} is not UTF-8; expected a UTF-8 JSON file",
                e.valid_up_to()
            ),
        })?;
        let base = path.parent().unwrap_or_else(|| Path::new(""));
        Self::from_json_str(&source, text, base)
    }

    /// Parses and validates rig.json text; `source` names it in messages and
    /// relative calibration paths are resolved against `base_dir`.
    pub fn from_json_str(source: &str, text: &str, base_dir: &Path) -> Result<Self, IoError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let value: Value =
            serde_json::from_str(text).map_err(|e| crate::error::json_error(source, &e))?;
        let fields = Fields { source };
        let top = value
            .as_object()
            .ok_or_else(|| fields.error("(top level)", "expected a JSON object", &value))?;
        let format = fields.get(top, "", "format")?;
        if format.as_str() != Some(RIG_FORMAT) {
            return Err(fields.error(
                "format",
                &format!("expected \"{RIG_FORMAT}\" (this is not a psdcal rig file)"),
                format,
            ));
        }
        let version_value = fields.get(top, "", "version")?;
        let version = version_value
            .as_u64()
            .filter(|v| *v >= 1)
            .ok_or_else(|| fields.error("version", "expected a positive integer", version_value))?;
        if version > u64::from(RIG_VERSION) {
            return Err(IoError::Field {
                file: source.to_string(),
                field: "version".into(),
                message: format!(
                    "version {version} was written by a newer psdcal; this psdcal reads rig \
                     files up to version {RIG_VERSION}"
                ),
            });
        }
        let sensors_value = fields.get(top, "", "sensors")?;
        let list = sensors_value.as_array().ok_or_else(|| {
            fields.error("sensors", "expected an array of sensors", sensors_value)
        })?;
        if list.len() < 2 {
            return Err(IoError::Field {
                file: source.to_string(),
                field: "sensors".into(),
                message: format!(
                    "the rig has {} sensor(s); expected at least 2 (a position from rays needs \
                     two sensors): list the entries of several sensors in one rig.json (each \
                     sensor's calibrate-in-situ --poses-out gives its entry); one sensor's \
                     angles need no rig: psdcal aoa --calibration",
                    list.len()
                ),
            });
        }
        let mut sensors: Vec<RigSensorRecord> = Vec::with_capacity(list.len());
        let mut seen: HashMap<String, usize> = HashMap::with_capacity(list.len());
        for (i, item) in list.iter().enumerate() {
            let sensor = fields.sensor(&format!("sensors[{i}]"), item, base_dir)?;
            if let Some(&k) = seen.get(&sensor.id) {
                return Err(IoError::Field {
                    file: source.to_string(),
                    field: format!("sensors[{i}].id"),
                    message: format!(
                        "id '{}' is already used by sensors[{k}]; expected unique ids",
                        sensor.id
                    ),
                });
            }
            seen.insert(sensor.id.clone(), i);
            sensors.push(sensor);
        }
        Ok(Self {
            source: source.to_string(),
            version: version as u32,
            sensors,
        })
    }

    /// Every sensor's index by id (a lookup in constant time, for large
    /// rigs).
    pub fn index(&self) -> HashMap<&str, usize> {
        self.sensors
            .iter()
            .enumerate()
            .map(|(k, s)| (s.id.as_str(), k))
            .collect()
    }

    /// Index of the sensor called `id`.
    pub fn index_of(&self, id: &str) -> Option<usize> {
        self.sensors.iter().position(|s| s.id == id)
    }

    /// The sensors' ids, comma-separated (for messages).
    pub fn ids(&self) -> String {
        self.sensors
            .iter()
            .map(|s| s.id.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Field readers that name the file and the field in their errors.
struct Fields<'a> {
    source: &'a str,
}

impl Fields<'_> {
    fn error(&self, field: &str, expected: &str, found: &Value) -> IoError {
        IoError::Field {
            file: self.source.to_string(),
            field: field.to_string(),
            message: format!("{expected}, found {}", shown(found)),
        }
    }

    fn get<'v>(
        &self,
        object: &'v Map<String, Value>,
        prefix: &str,
        name: &str,
    ) -> Result<&'v Value, IoError> {
        object.get(name).ok_or_else(|| IoError::Field {
            file: self.source.to_string(),
            field: join(prefix, name),
            message: "missing; see docs/positioning.md, 'Rig files', for the format".into(),
        })
    }

    fn sensor(&self, at: &str, item: &Value, base_dir: &Path) -> Result<RigSensorRecord, IoError> {
        let object = item
            .as_object()
            .ok_or_else(|| self.error(at, "expected a sensor object", item))?;
        let id_value = self.get(object, at, "id")?;
        let id = match id_value {
            Value::String(s) if !s.trim().is_empty() => s.trim().to_string(),
            Value::Number(n) if n.is_i64() || n.is_u64() => n.to_string(),
            other => {
                return Err(self.error(
                    &join(at, "id"),
                    "expected a non-empty text or integer identifier",
                    other,
                ))
            }
        };
        let cal_value = self.get(object, at, "calibration")?;
        let calibration = match cal_value {
            Value::String(s) if !s.trim().is_empty() => s.clone(),
            other => {
                return Err(self.error(
                    &join(at, "calibration"),
                    "expected the path of a calibration.json (text)",
                    other,
                ))
            }
        };
        let given: Vec<PoseFrame> = [PoseFrame::WorldFromSensor, PoseFrame::SensorFromWorld]
            .into_iter()
            .filter(|f| object.contains_key(f.field()))
            .collect();
        let given_as = match given.as_slice() {
            [one] => *one,
            [] => {
                return Err(IoError::Field {
                    file: self.source.to_string(),
                    field: join(at, "world_from_sensor"),
                    message: "missing; expected the sensor's pose as 'world_from_sensor' (or \
                              'sensor_from_world') with 'rvec' (rad) and 't_mm' (mm)"
                        .into(),
                })
            }
            _ => {
                return Err(IoError::Field {
                    file: self.source.to_string(),
                    field: join(at, "sensor_from_world"),
                    message: "the sensor has both 'world_from_sensor' and 'sensor_from_world'; \
                              expected exactly one of them"
                        .into(),
                })
            }
        };
        let pose_at = join(at, given_as.field());
        let pose_value = &object[given_as.field()];
        let pose_object = pose_value.as_object().ok_or_else(|| {
            self.error(
                &pose_at,
                "expected an object with 'rvec' and 't_mm'",
                pose_value,
            )
        })?;
        let rvec = self.vector3(&pose_at, pose_object, "rvec", "radians")?;
        let t = self.vector3(&pose_at, pose_object, "t_mm", "mm")?;
        let pose = Pose::new(rvec, t);
        let world_from_sensor = match given_as {
            PoseFrame::WorldFromSensor => pose,
            PoseFrame::SensorFromWorld => pose.inverse(),
        };
        let written = Path::new(&calibration);
        let calibration_path = if written.is_absolute() {
            written.to_path_buf()
        } else {
            base_dir.join(written)
        };
        Ok(RigSensorRecord {
            id,
            calibration,
            calibration_path,
            world_from_sensor,
            given_as,
        })
    }

    fn vector3(
        &self,
        at: &str,
        object: &Map<String, Value>,
        name: &str,
        unit: &str,
    ) -> Result<Vector3<f64>, IoError> {
        let value = self.get(object, at, name)?;
        let numbers: Option<Vec<f64>> = value
            .as_array()
            .filter(|a| a.len() == 3)
            .and_then(|a| a.iter().map(Value::as_f64).collect());
        match numbers {
            Some(v) if v.iter().all(|x| x.is_finite()) => Ok(Vector3::new(v[0], v[1], v[2])),
            _ => Err(self.error(
                &join(at, name),
                &format!("expected an array of 3 numbers ({unit})"),
                value,
            )),
        }
    }
}

fn join(prefix: &str, name: &str) -> String {
    if prefix.is_empty() {
        name.to_string()
    } else {
        format!("{prefix}.{name}")
    }
}

/// A JSON value for messages, shortened.
fn shown(value: &Value) -> String {
    const MAX_CHARS: usize = 60;
    let text = value.to_string();
    if text.chars().count() > MAX_CHARS {
        let short: String = text.chars().take(MAX_CHARS).collect();
        format!("{short}…")
    } else {
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const VALID: &str = r#"{
  "format": "psdcal-rig", "version": 1, "note": "ignored",
  "sensors": [
    {"id": "north", "calibration": "north.json",
     "world_from_sensor": {"rvec": [0.0, 0.0, 0.0], "t_mm": [0.0, 0.0, 2500.0]}},
    {"id": 2, "calibration": "/abs/east.json",
     "sensor_from_world": {"rvec": [0.0, 0.5, 0.0], "t_mm": [-1500.0, 0.0, 300.0]}}
  ]
}"#;

    fn parse(text: &str) -> Result<RigFile, IoError> {
        RigFile::from_json_str("rig.json", text, Path::new("/rigs"))
    }

    #[test]
    fn reads_both_pose_forms_and_resolves_paths() {
        let rig = parse(VALID).unwrap();
        assert_eq!(rig.version, 1);
        assert_eq!(rig.ids(), "north, 2");
        let north = &rig.sensors[0];
        assert_eq!(north.calibration_path, Path::new("/rigs/north.json"));
        assert_eq!(north.given_as, PoseFrame::WorldFromSensor);
        assert_eq!(north.world_from_sensor.t, Vector3::new(0.0, 0.0, 2500.0));
        let east = &rig.sensors[1];
        assert_eq!(east.calibration_path, Path::new("/abs/east.json"));
        assert_eq!(east.given_as, PoseFrame::SensorFromWorld);
        // world_from_sensor is the inverse of what was written.
        let written = Pose::new(
            Vector3::new(0.0, 0.5, 0.0),
            Vector3::new(-1500.0, 0.0, 300.0),
        );
        let p = Vector3::new(10.0, -20.0, 30.0);
        let back = east.world_from_sensor.transform(&written.transform(&p));
        assert!((back - p).norm() < 1e-12);
        assert_eq!(rig.index_of("2"), Some(1));
    }

    /// Each malformed file names the field at fault.
    #[test]
    fn malformed_files_name_the_field() {
        let cases: [(&str, &str, &str); 12] = [
            ("psdcal-rig", "[]", "(top level)"),
            (
                "\"format\": \"psdcal-rig\"",
                "\"format\": \"psdcal-calibration\"",
                "format",
            ),
            ("\"version\": 1", "\"version\": 0", "version"),
            ("\"version\": 1", "\"version\": 2", "version"),
            ("\"id\": \"north\", ", "", "sensors[0].id"),
            ("\"id\": 2", "\"id\": \"north\"", "sensors[1].id"),
            ("\"id\": 2", "\"id\": \"\"", "sensors[1].id"),
            (
                "\"calibration\": \"north.json\"",
                "\"calibration\": 7",
                "sensors[0].calibration",
            ),
            (
                "[0.0, 0.0, 2500.0]",
                "[0.0, 2500.0]",
                "sensors[0].world_from_sensor.t_mm",
            ),
            (
                "[0.0, 0.5, 0.0]",
                "[0.0, \"x\", 0.0]",
                "sensors[1].sensor_from_world.rvec",
            ),
            (
                "\"sensor_from_world\"",
                "\"world_from_sensor\": {}, \"sensor_from_world\"",
                "sensors[1].sensor_from_world",
            ),
            (
                "\"sensor_from_world\"",
                "\"pose\"",
                "sensors[1].world_from_sensor",
            ),
        ];
        for (from, to, field) in cases {
            let text = if from == "psdcal-rig" {
                to.to_string()
            } else {
                VALID.replacen(from, to, 1)
            };
            assert_ne!(text, VALID, "case {field}: replacement did nothing");
            let e = parse(&text).unwrap_err();
            match &e {
                IoError::Field {
                    file, field: got, ..
                } => {
                    assert_eq!(file, "rig.json");
                    assert_eq!(got, field, "{e}");
                }
                other => panic!("case {field}: expected a field error, got {other}"),
            }
            assert!(
                e.to_string()
                    .starts_with(&format!("rig.json: field '{field}': ")),
                "{e}"
            );
        }
        let e = parse(r#"{"format": "psdcal-rig", "version": 1, "sensors": [{"id": "a"}]}"#)
            .unwrap_err();
        assert!(e.to_string().contains("expected at least 2"), "{e}");
        let e = parse(&VALID.replace("2500.0]", "1e999]")).unwrap_err();
        assert!(
            matches!(e, IoError::Json { .. } | IoError::Field { .. }),
            "{e}"
        );
        let e = parse("{\"format\": ").unwrap_err();
        assert!(matches!(e, IoError::Json { line: 1, .. }), "{e}");
    }

    #[test]
    fn reading_a_missing_file_names_it() {
        let e = read_rig("/nonexistent/rig.json").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("/nonexistent/rig.json: cannot read"),
            "{e}"
        );
    }
}
