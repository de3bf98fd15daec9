//! The HTML pages with their plots: a calibration report and a PSD map report.

pub(crate) mod calibration_page;
pub(crate) mod calibration_plots;
pub(crate) mod calibration_tables;
pub(crate) mod calibration_views;
pub(crate) mod choice_table;
pub(crate) mod psd_map_page;
