//! The rules a calibration.json must follow beyond its JSON shape: format
//! name and version, finite and positive numbers, consistent parameter
//! lists, `std` and covariance names. Field-level rules also run while
//! parsing (the `de_*` functions), so that their errors carry the JSON line
//! and column; [`Calibration::validate`] runs them all, before writing too.

use std::collections::HashSet;

use serde::de::{self, Deserializer};
use serde::Deserialize;

use super::{Calibration, CALIBRATION_FORMAT, CALIBRATION_VERSION};

impl Calibration {
    pub(super) fn check(&self) -> Result<(), String> {
        check_format(&self.format)?;
        check_version(u64::from(self.version))?;
        check_positive("sensor.lx_mm", self.sensor.lx_mm)?;
        check_positive("sensor.ly_mm", self.sensor.ly_mm)?;
        check_at_most("sensor.lx_mm", self.sensor.lx_mm, MAX_SENSOR_MM)?;
        check_at_most("sensor.ly_mm", self.sensor.ly_mm, MAX_SENSOR_MM)?;
        let i = &self.intrinsics;
        check_positive("intrinsics.f_mm", i.f_mm)?;
        check_at_least("intrinsics.f_mm", i.f_mm, MIN_FOCAL_MM)?;
        check_at_most("intrinsics.f_mm", i.f_mm, MAX_FOCAL_MM)?;
        for (name, value) in [
            ("intrinsics.cx_mm", i.cx_mm),
            ("intrinsics.cy_mm", i.cy_mm),
            ("intrinsics.skew", i.skew),
        ] {
            check_finite(name, value)?;
        }
        check_at_most("|intrinsics.cx_mm|", i.cx_mm.abs(), MAX_SENSOR_MM)?;
        check_at_most("|intrinsics.cy_mm|", i.cy_mm.abs(), MAX_SENSOR_MM)?;
        check_skew(i.skew, i.f_mm)?;
        let d = &self.distortion;
        for (name, value) in [
            ("k1", d.k1),
            ("k2", d.k2),
            ("k3", d.k3),
            ("p1", d.p1),
            ("p2", d.p2),
            ("l1", d.l1),
            ("l2", d.l2),
        ] {
            check_finite(&format!("distortion.{name}"), value)?;
        }
        self.check_parameter_lists()?;
        if let Some(g) = &self.gains {
            g.check()?;
        }
        self.check_uncertainty()?;
        if let Some(region) = &self.valid_region {
            region.to_region(&self.geometry())?;
        }
        self.check_fit()
    }

    fn check_parameter_lists(&self) -> Result<(), String> {
        for (list, params) in [("estimated", &self.estimated), ("fixed", &self.fixed)] {
            let mut seen = HashSet::new();
            if let Some(p) = params.iter().find(|p| !seen.insert(**p)) {
                return Err(format!("'{list}' lists '{p}' twice; expected each once"));
            }
        }
        if let Some(p) = self.estimated.iter().find(|p| self.fixed.contains(p)) {
            return Err(format!(
                "'{p}' is both estimated and fixed; expected each parameter in one list"
            ));
        }
        Ok(())
    }

    fn check_uncertainty(&self) -> Result<(), String> {
        let expected = self.estimated_names();
        let names = self.std.names();
        for (name, value) in &self.std.0 {
            if !(value.is_finite() && *value >= 0.0) {
                return Err(format!(
                    "std.{name} must be zero or a positive number, found {}",
                    shown(*value)
                ));
            }
        }
        let mut sorted_names = names.clone();
        sorted_names.sort_unstable();
        let mut sorted_expected = expected.clone();
        sorted_expected.sort_unstable();
        if sorted_names != sorted_expected {
            return Err(format!(
                "'std' has entries [{}]; expected one per estimated parameter: [{}]",
                names.join(", "),
                expected.join(", ")
            ));
        }
        self.covariance.check()?;
        self.covariance.check_positive_semidefinite()?;
        if self.covariance.parameters != names {
            return Err(format!(
                "covariance.parameters [{}] must list the names of 'std' in the same order: [{}]",
                self.covariance.parameters.join(", "),
                names.join(", ")
            ));
        }
        self.check_std_matches_covariance()
    }

    /// Each `std` entry is the square root of its covariance variance (to
    /// 1e-6 relative: the file keeps both, and a hand edit of one alone
    /// would make the printed σ and the propagated σ disagree).
    fn check_std_matches_covariance(&self) -> Result<(), String> {
        for (name, value) in &self.std.0 {
            let Some(variance) = self.covariance.get(name, name) else {
                continue;
            };
            let expected = variance.sqrt();
            if (value - expected).abs() > STD_TOLERANCE * value.max(expected) {
                return Err(format!(
                    "std.{name} is {} but the square root of its covariance entry is {}; \
                     expected them equal (was one of them edited?)",
                    shown(*value),
                    shown(expected)
                ));
            }
        }
        Ok(())
    }

    fn check_fit(&self) -> Result<(), String> {
        let f = &self.fit;
        for (name, value) in [
            ("fit.residual_mm2", f.residual_mm2),
            ("fit.rms_template_mm", f.rms_template_mm),
            ("fit.rms_image_mm", f.rms_image_mm),
        ] {
            check_non_negative(name, value)?;
        }
        let mut ids = HashSet::new();
        for (k, image) in self.images.iter().enumerate() {
            if !ids.insert(image.id.as_str()) {
                return Err(format!(
                    "images[{k}]: image id '{}' appears twice; expected unique ids",
                    image.id
                ));
            }
            for (name, values) in [("rvec", image.rvec), ("t_mm", image.t_mm)] {
                if values.iter().any(|v| !v.is_finite()) {
                    return Err(format!("images[{k}].{name} must hold finite numbers"));
                }
            }
            check_non_negative(&format!("images[{k}].rms_mm"), image.rms_mm)?;
        }
        Ok(())
    }
}

/// A number for messages: its value when finite, else a word.
pub(super) fn shown(value: f64) -> String {
    if value.is_finite() {
        crate::number_text::number_text(value)
    } else {
        "a non-finite value".to_string()
    }
}

pub(super) fn check_format(format: &str) -> Result<(), String> {
    if format == CALIBRATION_FORMAT {
        Ok(())
    } else {
        Err(format!(
            "\"format\" is \"{}\"; expected \"{CALIBRATION_FORMAT}\" (this is not a psdcal \
             calibration file)",
            crate::limits::excerpt(format).escape_debug()
        ))
    }
}

pub(super) fn check_version(version: u64) -> Result<(), String> {
    if version <= u64::from(CALIBRATION_VERSION) {
        Ok(())
    } else {
        Err(format!(
            "format version {version} was written by a newer psdcal; this psdcal reads versions \
             up to {CALIBRATION_VERSION}"
        ))
    }
}

pub(super) fn check_finite(name: &str, value: f64) -> Result<(), String> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(format!("{name} must be a finite number"))
    }
}

/// The largest active-area side and optical-centre offset accepted, mm (a
/// PSD is millimetres across: a larger value is a unit or typing error).
pub(super) const MAX_SENSOR_MM: f64 = 1000.0;
/// The largest focal length accepted, mm.
pub(super) const MAX_FOCAL_MM: f64 = 100_000.0;
/// The smallest focal length accepted, mm (10 µm: a shorter one puts a
/// millimetre-sized active area at grazing angles; a smaller value is a unit
/// or typing error).
pub(super) const MIN_FOCAL_MM: f64 = 0.01;
/// The largest skew accepted, as a fraction of f: `|γ| < f`, the pixel axes
/// more than 45° apart (a real sensor's skew is near 0).
pub(super) const MAX_SKEW_OVER_F: f64 = 1.0;
/// Relative agreement of a `std` entry with its covariance's variance.
pub(super) const STD_TOLERANCE: f64 = 1e-6;

fn check_skew(skew: f64, f: f64) -> Result<(), String> {
    if skew.abs() < MAX_SKEW_OVER_F * f {
        Ok(())
    } else {
        Err(format!(
            "|intrinsics.skew| is {}, not below f ({} mm); expected a skew far below the focal \
             length (a real sensor's is near 0)",
            shown(skew.abs()),
            shown(f)
        ))
    }
}

pub(super) fn check_at_least(name: &str, value: f64, min: f64) -> Result<(), String> {
    if value >= min {
        Ok(())
    } else {
        Err(format!(
            "{name} is {}, below the plausible {}; expected a value in mm (check the unit)",
            shown(value),
            shown(min)
        ))
    }
}

pub(super) fn check_at_most(name: &str, value: f64, max: f64) -> Result<(), String> {
    if value <= max {
        Ok(())
    } else {
        Err(format!(
            "{name} is {}, beyond the plausible {}; expected a value in mm (check the unit)",
            shown(value),
            shown(max)
        ))
    }
}

pub(super) fn check_positive(name: &str, value: f64) -> Result<(), String> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "{name} must be a positive number, found {}",
            shown(value)
        ))
    }
}

pub(super) fn check_non_negative(name: &str, value: f64) -> Result<(), String> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(format!(
            "{name} must be zero or a positive number, found {}",
            shown(value)
        ))
    }
}

pub(super) fn de_format<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    let format = String::deserialize(d)?;
    check_format(&format).map_err(de::Error::custom)?;
    Ok(format)
}

pub(super) fn de_version<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    let version = u64::deserialize(d)?;
    check_version(version).map_err(de::Error::custom)?;
    u32::try_from(version).map_err(de::Error::custom)
}

pub(super) fn de_positive<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let value = f64::deserialize(d)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(de::Error::custom(format!(
            "expected a positive number of mm, found {}",
            shown(value)
        )))
    }
}

pub(super) fn de_identifier<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Id {
        Text(String),
        Integer(i64),
    }
    match Id::deserialize(d) {
        Ok(Id::Text(s)) => Ok(s),
        Ok(Id::Integer(n)) => Ok(n.to_string()),
        Err(_) => Err(de::Error::custom(
            "expected an image identifier (a string or an integer)",
        )),
    }
}
