//! # psdcal-study
//!
//! The Monte Carlo studies that reproduce and extend the paper's evaluation
//! (its Section 4, Tables 1–10 and Figure 9): each condition is simulated
//! through the whole signal chain by psdcal-sim and calibrated by
//! psdcal-calib over seeded trials.
//!
//! - [`study`]: table conditions, seeded trials (thread-count independent),
//!   statistics; [`run_tables`] runs them on the current rayon pool;
//! - [`paper`]: the paper's Tables 1–10 as printed;
//! - [`render`]: study tables as Markdown and CSV beside the paper's numbers;
//! - [`fig9`]: Figure 9's error maps from the study's parameter errors;
//! - [`insitu`]: in-situ calibration trials from surveyed emitters;
//! - [`SimulationData`]: a simulated data set as the calibration's input.
#![warn(missing_docs)]

mod data;
pub mod fig9;
pub mod insitu;
pub mod paper;
pub mod planned;
pub mod render;
pub mod study;
pub mod tables;

pub use data::SimulationData;
pub use psdcal_sim::{Lens, SimError, TemplateKind};
pub use study::{
    run_tables, table_spec, Condition, Method, Quantity, StudyOptions, TableResult, TableSpec,
    TABLE_IDS,
};
