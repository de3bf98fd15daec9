//! # psdcal
//!
//! Calibrate position-sensitive-device (PSD) sensors for infrared
//! positioning, and use them: the library behind the `psdcal` command.
//! Files in, calibration out, angles of arrival out:
//!
//! ```
//! use std::path::PathBuf;
//!
//! use psdcal::{
//!     calibrate, CalibrationOptions, DataSet, DataSetFiles, LoadOptions, LocateOptions,
//!     Measurement, PointSource,
//! };
//! use nalgebra::Vector2;
//!
//! # fn main() -> Result<(), psdcal::Error> {
//! let example = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/example");
//! // The data set: the template and the measured points of nine images.
//! let set = DataSet::from_files(
//!     &DataSetFiles {
//!         template: example.join("template.csv"),
//!         points: PointSource::Observations(example.join("observations.csv")),
//!         gains: None,
//!     },
//!     &LoadOptions::default(),
//! )?;
//! // Calibrate f, cx, cy, k1, k2 from automatic initialisation.
//! let calibrated = calibrate(&set, &CalibrationOptions::default())?;
//! assert!((calibrated.report.parameters[0].value - 8.0).abs() < 1e-6);
//! // calibrated.write(&set, "calibration.json".as_ref(), None)? writes it.
//!
//! // The calibrated sensor turns a measured point into angles of arrival.
//! let sensor = psdcal::sensor_of(&calibrated.record)?;
//! let answer = sensor.aoa(
//!     &Measurement::Point(Vector2::new(1.0, -0.5)),
//!     &LocateOptions::default(),
//! )?;
//! let (ax, ay) = (answer.aoa.alpha.x.to_degrees(), answer.aoa.alpha.y.to_degrees());
//! println!("alpha_x = {ax:.4}°, alpha_y = {ay:.4}°");
//! assert!(ax > 0.0 && ay > 0.0);
//! # Ok(())
//! # }
//! ```
//!
//! | job | entry point |
//! | --- | --- |
//! | read and validate a data set (files or memory) | [`DataSet`] |
//! | calibrate it, write calibration.json (version 2) and residuals | [`calibrate()`], [`Calibrated`] |
//! | a calibration file (version 1 or 2) as a sensor | [`LoadedSensor`], [`sensor_of`] |
//! | measured → ideal points, angles of arrival, positions, error maps | [`correct()`], [`aoa_table`], [`locate_table`], [`map_table`] |
//! | electrical gains | [`estimate_gains`] |
//! | the PSD's non-linearity map from a lensless scan (and its report page) | [`psd_map_from_scan`], [`PsdMapOutcome::write`], [`simulate_scan_file`] |
//! | positions (and angles) against a surveyed truth: the standard metrics | [`evaluate()`] |
//! | raw recordings → signals.csv (band-pass, lock-in, SNR) | [`demodulate()`] |
//! | a live stream of samples → angles per window and LED | [`track()`] |
//! | the same from arrays in memory (front ends such as the Python package) | [`arrays`], [`simulate_data`], [`error_text`] |
//! | simulate a data set, the demo, the paper's study | [`simulate_files`], [`demo()`], [`plan_study`] |
//! | simulate a calibrated rig and emitters (rig.json, rig_points.csv, truth.csv) | [`simulate_positioning()`] |
//! | a calibration report (HTML and plots) | [`write_report`] |
//! | a calibration as an OpenCV, mrcal or ROS camera model | [`export()`] |
//! | two calibrations compared in angles, with the combined σ | [`diff()`] |
//!
//! Every failure is an [`Error`]; nothing here prints, and every output
//! file is written atomically.
#![warn(missing_docs)]

mod answer;
mod base;
mod calibration;
mod dataset;
mod frontend;
mod live;
mod network;
mod psd_map;
mod reports;
mod signals;
mod simulation;
mod study;

pub use base::option_text;
pub use frontend::arrays;
pub use network::calibrate_network::{calibrate_network_files, NetworkCalibrated, NetworkRequest};
pub use network::network_input::{read_network, NetworkFiles, NetworkInput};
pub use network::network_page::network_page;
pub use network::simulate_network::{simulate_network, NetworkSimRequest};

pub use answer::aoa::{aoa_table, measurement, AoaTable};
pub use answer::correct::{correct, Corrected};
pub use answer::diff::{diff, DiffRequest, Diffed, DEFAULT_DIFF_GRID, DIFF_COLUMNS};
pub use answer::evaluate::{evaluate, EvaluateRequest, Evaluation};
pub use answer::export::{
    export, ExportRequest, ExportTarget, Exported, DEFAULT_MAX_ERROR_DEG, DEFAULT_PIXEL_UM,
};
pub use answer::focal_check::{focal_check, FocalCheck, FocalCheckRequest};
pub use answer::loaded_sensor::{covariance_warning, save_calibration, sensor_of, LoadedSensor};
pub use answer::locate::{locate_table, LocateTable, LocateTarget};
pub use answer::map::{map_table, MapModel, MapRequest, MapSource, MapSourceError, MapTable};
pub use answer::point_rows::{answer_points, PointsAnswer, RowAnswer};
pub use base::advice::{advice, error_text};
#[cfg(feature = "clap")]
pub use base::command_files::refuse_input_overwrite;
pub use base::error::{Error, Result};
pub use base::option_text::plane_at_distance;
pub use base::options::CalibrationOptions;
pub use base::provenance::{provenance, sha256_hex, utc_iso8601, InputHashes};
pub use base::stdout::{is_closed_output, print_text, write_stdout, STANDARD_OUTPUT};
pub use base::summary::Summary;
pub use base::summary_text::summary_text;
pub use base::table::{deg, num, StatusCount, Table, MAX_ROW_WARNINGS};
pub use calibration::calibrate::{calibrate, Calibrated};
pub use calibration::calibrate_options::{
    calibrate_settings, CalibrateSettings, CALIBRATE_OPTION_NAMES,
};
pub use calibration::fit_report::{FitReport, GlobalSearch, ImageRow, ParameterRow};
pub use calibration::gains::{estimate_gains, gains_summary, GainsMethod};
pub use calibration::in_situ::{calibrate_in_situ, position_with_jacobian, InSitu, SensorPose};
pub use calibration::residuals::{ImageResiduals, Residual, ResidualTable};
pub use dataset::data_set::{
    source_path, DataSet, DataSetFiles, LoadOptions, MemoryPoints, PointSource,
};
pub use live::serve::{serve, ServeRequest, ServeSummary};
pub use psd_map::from_scan::{
    parse_psd_map_model, psd_map_from_scan, PsdMapOutcome, PsdMapRequest, PSD_MAP_PAGE,
    RESIDUAL_MAP_CELLS, SCAN_SUMMARY_CELLS,
};
pub use psdcal_calib::{
    BootstrapOptions, ModelChoice, NoiseModel, Preliminary, RobustLoss, Uncertainty,
};
pub use psdcal_io::RawFormat;
pub use psdcal_model::CostKind;
pub use psdcal_psdmap::ModelChoice as PsdMapModel;
pub use psdcal_signal::DemodConfig;
pub use psdcal_sim::{Impairment, Impairments};
pub use reports::calibration_page::{report_content, write_report, ReportFiles, ReportRequest};
pub use signals::demodulate::{
    demodulate, DemodulateRequest, Demodulated, RecordOutcome, RecordStatus, MAX_RECORD_SAMPLES,
};
pub use signals::track::{track, TrackRequest, TrackSummary, TrackTarget};
pub use signals::track_rig::LedFix;
pub use simulation::demo::{demo, Demo, DemoParameter};
pub use simulation::plan::{plan_poses, PlanRequest, Planned};
pub use simulation::simulate::{
    chain_with_record, parse_record_cycles, record_cycles_flag, simulate_data, simulate_files,
    simulate_files_at_poses, transient_cycles, SimulateRequest, SimulatedData, SimulatedFiles,
    DEFAULT_RECORD_CYCLES, MAX_RECORD_CYCLES,
};
pub use simulation::simulate_moving::{
    simulate_moving, MovingRequest, SimulatedMoving, DEFAULT_MOVING_NOISE_V, MOVING_SAMPLE_RATE_HZ,
};
pub use simulation::simulate_positioning::{
    simulate_positioning, PositioningRequest, SimulatedRig,
};
pub use simulation::simulate_raw::{
    simulate_raw_files, RawRequest, FDMA_SPACING_HZ, RAW_F0_HZ, RAW_SAMPLE_RATE_HZ,
};
pub use simulation::simulate_scan::{scan_samples, simulate_scan_file, ScanRequest, SimulatedScan};
pub use study::monte_carlo::{
    expand_tables, is_study_id, parse_study_id, plan_study, study_ids, StudyOutcome, StudyPlan,
    StudyRequest,
};
pub use study::study_psd_map::{pooled, psd_map_seed, SeedErrors};
#[cfg(feature = "testing")]
pub use study::testing::{refine_seed, RefineErrors, ScanSpec};

pub use psdcal_calib::CalibError;
pub use psdcal_io::{Calibration, IoError, ReadLimits, Warning};
pub use psdcal_locate::LocateError;
pub use psdcal_locate::{CalibratedSensor, LocateOptions, Measurement, Plane, MAX_GRID};
pub use psdcal_locate::{CvOptions, TrackFilter};
pub use psdcal_model::{Diagnostic, DiagnosticCode, Severity};
pub use psdcal_model::{Param, PsdGeometry};
pub use psdcal_sim::room::RoomOptions;
pub use psdcal_sim::{Lens, TemplateKind};
