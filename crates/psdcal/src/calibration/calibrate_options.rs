//! A calibration's options given by name as text (`fit = "f,cx,cy"`,
//! `robust = "huber:2.5"`, `lx = "9"`): the command line's `calibrate`
//! options without their `--` (`-` or `_` between words), each parsed by
//! [`crate::base::option_text`]'s parser of that option, so that a front end
//! without clap (the Python package's keywords) accepts and refuses the same
//! values with the same words.

use std::path::PathBuf;

use psdcal_model::PsdGeometry;

use crate::base::option_text::{
    parse_assignment, parse_fit, parse_robust, parse_switch, parse_uncertainty, positive_mm,
    side_mm,
};
use crate::base::options::CalibrationOptions;
use crate::dataset::data_set::LoadOptions;

/// The names accepted, in the command line's order.
pub const CALIBRATE_OPTION_NAMES: [&str; 15] = [
    "fit",
    "focal_guess",
    "cost",
    "noise",
    "preliminary",
    "normalize",
    "robust",
    "uncertainty",
    "psd_map",
    "refine_psd_map",
    "set",
    "gains",
    "lx",
    "ly",
    "strict",
];

/// Everything `calibrate` is told besides its data.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CalibrateSettings {
    /// The calibration's options.
    pub options: CalibrationOptions,
    /// How the data set is validated (active area, strict).
    pub load: LoadOptions,
    /// gains.json of an electrical calibration (`gains`).
    pub gains: Option<PathBuf>,
}

/// Parses `(name, values)` pairs (`set` may have several values, every
/// other option one) into settings; an unknown name, a repeated value or a
/// value its parser refuses is an error naming the option.
pub fn calibrate_settings(pairs: &[(String, Vec<String>)]) -> Result<CalibrateSettings, String> {
    let mut s = CalibrateSettings::default();
    let mut geometry = PsdGeometry::default();
    for (given, values) in pairs {
        let name = given.trim().trim_start_matches("--").replace('-', "_");
        if !CALIBRATE_OPTION_NAMES.contains(&name.as_str()) {
            return Err(format!(
                "unknown option '{given}' (expected one of {})",
                CALIBRATE_OPTION_NAMES.join(", ")
            ));
        }
        let one = || -> Result<&str, String> {
            match values.as_slice() {
                [v] => Ok(v.as_str()),
                _ => Err(format!("option {name}: expected one value")),
            }
        };
        let named = |e: String| format!("option {name}: {e}");
        let o = &mut s.options;
        match name.as_str() {
            "fit" => {
                let fit = parse_fit(one()?).map_err(named)?;
                o.free = fit.params;
                o.fit_gains = fit.gains;
                o.fit_aspect = fit.aspect;
                o.choice = psdcal_calib::ModelChoice::Given;
            }
            "focal_guess" => o.focal_guess = Some(positive_mm(one()?).map_err(named)?),
            "cost" => o.cost = one()?.parse().map_err(named)?,
            "noise" => o.noise = one()?.parse().map_err(named)?,
            "preliminary" => o.preliminary = one()?.parse().map_err(named)?,
            "normalize" => o.normalize = parse_switch(one()?).map_err(named)?,
            "robust" => o.robust = Some(parse_robust(one()?).map_err(named)?),
            "uncertainty" => o.uncertainty = parse_uncertainty(one()?).map_err(named)?,
            "psd_map" => o.psd_map = Some(PathBuf::from(one()?)),
            "refine_psd_map" => o.refine_psd_map = parse_switch(one()?).map_err(named)?,
            "set" => {
                for v in values {
                    let (p, x) = parse_assignment(v).map_err(named)?;
                    if o.fixed.iter().any(|(q, _)| *q == p) {
                        return Err(named(format!("{p} is set twice")));
                    }
                    o.fixed.push((p, x));
                }
            }
            "gains" => s.gains = Some(PathBuf::from(one()?)),
            "lx" => geometry.lx = side_mm(one()?).map_err(named)?,
            "ly" => geometry.ly = side_mm(one()?).map_err(named)?,
            _ => s.load.strict = parse_switch(one()?).map_err(named)?,
        }
    }
    s.load.geometry = geometry;
    Ok(s)
}

#[cfg(test)]
mod tests {
    use psdcal_model::Param;

    use super::*;

    fn pairs(items: &[(&str, &[&str])]) -> Vec<(String, Vec<String>)> {
        items
            .iter()
            .map(|(n, v)| (n.to_string(), v.iter().map(|s| s.to_string()).collect()))
            .collect()
    }

    #[test]
    fn options_parse_as_on_the_command_line() {
        let s = calibrate_settings(&pairs(&[
            ("fit", &["f,cx,cy,k1"]),
            ("cost", &["image"]),
            ("robust", &["huber:2.5"]),
            ("set", &["l1=-1.3e-3", "k2=0"]),
            ("focal-guess", &["8"]),
            ("lx", &["10"]),
            ("strict", &["True"]),
        ]))
        .unwrap();
        assert_eq!(s.options.free, [Param::F, Param::Cx, Param::Cy, Param::K1]);
        assert_eq!(s.options.cost, psdcal_model::CostKind::Image);
        assert_eq!(
            s.options.robust,
            Some(psdcal_calib::RobustLoss::Huber { scale: 2.5 })
        );
        assert_eq!(s.options.fixed, [(Param::L1, -1.3e-3), (Param::K2, 0.0)]);
        assert_eq!(s.options.focal_guess, Some(8.0));
        assert_eq!((s.load.geometry.lx, s.load.geometry.ly), (10.0, 9.0));
        assert!(s.load.strict);
        assert_eq!(
            calibrate_settings(&[]).unwrap(),
            CalibrateSettings::default()
        );
    }

    #[test]
    fn refusals_name_the_option_and_use_the_shared_words() {
        let e = calibrate_settings(&pairs(&[("focal_guess", &["-3"])])).unwrap_err();
        assert_eq!(
            e,
            format!("option focal_guess: {}", positive_mm("-3").unwrap_err())
        );
        let e = calibrate_settings(&pairs(&[("fit", &["f,zz"])])).unwrap_err();
        assert!(e.starts_with("option fit: "), "{e}");
        assert_eq!(e, format!("option fit: {}", parse_fit("f,zz").unwrap_err()));
        let e = calibrate_settings(&pairs(&[("colour", &["red"])])).unwrap_err();
        assert!(e.starts_with("unknown option 'colour'"), "{e}");
        let e = calibrate_settings(&pairs(&[("set", &["k1=1", "k1=2"])])).unwrap_err();
        assert!(e.contains("set twice"), "{e}");
    }
}
