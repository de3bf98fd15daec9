//! The HTML pages with their plots: a calibration report and a PSD map report.

pub(crate) mod psd_map_report;
pub(crate) mod report;
pub(crate) mod report_plots;
pub(crate) mod report_tables;
pub(crate) mod report_views;
