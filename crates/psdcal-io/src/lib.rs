//! # psdcal-io
//!
//! psdcal's file formats (the binding specification is docs/formats.md):
//!
//! - [`Template`] — template.csv, the LEDs of the calibration template;
//! - [`Observations`] — observations.csv, measured impact points per image;
//! - [`Signals`] — signals.csv, electrode amplitudes, converted to
//!   observations with the pin-cushion formulas of docs/model.md §1;
//! - [`Points`] — points.csv, points to correct or answer, read row by row
//!   (the facade writes each answer after the row's original columns);
//! - [`Calibration`] — calibration.json, versioned, read with
//!   [`read_calibration`] and written with [`write_calibration`];
//! - [`Scan`] — scan.csv, a lensless scan of the PSD (points or amplitudes);
//! - [`PsdMapFile`] — psd_map.json, a fitted PSD map ([`read_psd_map`],
//!   [`write_psd_map`]);
//! - [`RigFile`] — rig.json, sensors with poses in a world frame, and
//!   [`RigObservations`], what they measured per emitter.
//!
//! - [`CameraModelFile`] — camera models for OpenCV, mrcal and ROS
//!   ([`write_camera_model`], written by `psdcal export`).
//!
//! - [`RawReader`] — raw recordings (raw.csv, raw.npy, raw.tdms) read frame by frame;
//!   [`TdmsReader`] — any channels of an NI TDMS file, row by row
//!   in constant memory, with [`Schedule`] (schedule.csv) and [`Tones`]
//!   (tones.csv), the input of `demodulate`.
//!
//! [`validate_data_set`] checks a template and its observations together and
//! groups the usable points by image; [`DataSetSummary`] and [`Coverage`]
//! describe the result. Every output file is written atomically
//! ([`write_atomic`]).
//!
//! All readers take a path (named in messages) and also have `from_reader`
//! and `from_str` variants with a display name. Every error is an
//! [`IoError`] that names the file, the 1-based physical line and, for a bad
//! value, the column, and says what was expected. No input makes these
//! readers panic or produce a NaN. Millimetres everywhere.
#![warn(missing_docs)]

mod atomic;
mod calibration;
mod camera_model_file;
mod corners;
mod coverage;
mod csv_field;
mod csv_fields;
mod csv_lines;
mod csv_numeric;
#[macro_use]
mod csv_table;
mod error;
mod export;
mod gains_file;
mod limits;
mod location;
mod network_files;
mod number_text;
mod observations;
mod output_folder;
mod points;
mod poses;
mod positioning;
mod psd_map_file;
mod raw;
mod raw_csv;
mod raw_frame;
mod raw_rig;
mod rig;
mod rig_observations;
mod same_file;
mod sample_stream;
mod scan;
mod schedule;
mod signals;
mod summary;
mod tdms;
mod tdms_meta;
mod tdms_scaling;
mod tdms_write;
mod template;
mod truth;
mod validate;
mod warning;

pub use atomic::{write_atomic, write_atomic_at, write_atomic_bytes, PendingFile, STALE_AGE};
pub use calibration::{
    read_calibration, read_calibration_with, write_calibration, AspectRecord, BootstrapRecord,
    Calibration, CostKind, Covariance, Diagnostic, FitSummary, GainsRecord, ImageFit, InputFile,
    IntrinsicsRecord, Provenance, PsdMapScanRecord, PsdMapStageCovariance, PsdMapStageRecord,
    ScanResidualCells, SensorSize, Software, StdDevs, ValidRegionRecord, CALIBRATION_FORMAT,
    CALIBRATION_VERSION, GAIN_NAMES,
};
pub use camera_model_file::{float_text, write_camera_model, CameraFormat, CameraModelFile};
pub use corners::{Corner, Corners};
pub use coverage::{Bounds, Coverage};
pub use csv_field::csv_field;
pub use error::{ColumnRef, IoError, StreamFault};
pub use export::{
    write_observations, write_signals, write_template, ObservationRow, SignalRowOut, TemplateLed,
};
pub use gains_file::{read_gains, read_gains_with, write_gains, GainStd, GainsFile, GAINS_FORMAT};
pub use limits::{
    read_all_bounded, read_bounded, ReadLimits, DEFAULT_MAX_FILE_BYTES, MAX_EXCERPT_CHARS,
    MAX_LINE_BYTES,
};
pub use location::Location;
pub use network_files::{
    LedPositions, NetworkPointRow, NetworkPoints, NetworkSensorRow, NetworkSensors,
};
pub use number_text::{number_text, shown_number};
pub use observations::{Observation, ObservationText, Observations};
pub use output_folder::{OutputFolder, MANIFEST};
pub use points::{AddedColumn, PointInput, PointRow, PointStream, Points};
pub use poses::{write_poses, PoseRow, Poses};
pub use positioning::{EstimateRow, MatchedEstimate, PositionEstimates, PositionTruth, TruthRow};
pub use psd_map_file::{
    psd_map_from_reader, psd_map_from_reader_with, read_psd_map, read_psd_map_with, write_psd_map,
    LoadedPsdMap, MapCandidateRecord, MapCoefficients, MapCovarianceRecord, MapFitRecord,
    MapResidualsRecord, PsdMapFile, PSD_MAP_FORMAT, PSD_MAP_VERSION,
};
pub use raw::{
    npy_header, npy_header_columns, write_csv_frames, write_npy_frames, RawFormat, RawReader,
    RAW_CSV_HEADER,
};
pub use raw_frame::{Frame, RATE_TOLERANCE};
pub use rig::{
    read_rig, read_rig_with, PoseFrame, RigFile, RigSensorRecord, RIG_FORMAT, RIG_VERSION,
};
pub use rig_observations::{RigObservation, RigObservations};
pub use same_file::refuse_overwrite;
pub use sample_stream::{Sample, SampleSource};
pub use scan::{write_scan, Scan, ScanPoints, ScanReading, ScanRow, SCAN_DUPLICATE_MM};
pub use schedule::{write_schedule, write_tones, Schedule, ScheduleRow, Tone, Tones};
pub use signals::{SignalRow, Signals};
pub use summary::{DataSetSummary, ImageSummary, LineSummary, TemplateSummary};
pub use tdms::{TdmsReader, TDMS_DEFAULT_CHANNELS};
pub use tdms_write::TdmsFrameWriter;
pub use template::{Led, LineGroup, Template};
pub use truth::{
    read_truth, read_truth_with, write_truth, SimulationSettings, TrueGains, TruePose, Truth,
    TRUTH_FORMAT, TRUTH_VERSION,
};
pub use validate::{
    validate_data_set, DataSetValidator, Image, ValidatedDataSet, ValidationOptions, MIN_IMAGES,
    MIN_POINTS_PER_IMAGE,
};
pub use warning::Warning;
