//! Calibrating a sensor: the options, the fit, its report, calibration.json records and residuals, gains, in-situ calibration.

pub(crate) mod calibrate;
pub(crate) mod calibrate_map;
pub(crate) mod calibrate_options;
pub(crate) mod convert;
pub(crate) mod fit_report;
pub(crate) mod gains;
pub(crate) mod in_situ;
pub(crate) mod loaded_checks;
pub(crate) mod residuals;
