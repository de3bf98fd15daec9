//! Command-line arguments (clap) and the validated configuration they turn
//! into. Nothing here reads files: it only decides what to do.

use std::path::PathBuf;

use clap::{CommandFactory, Parser, Subcommand};
use psdcal::option_text::FitList;
pub use psdcal::PointSource;
use psdcal::{CalibrationOptions, DataSetFiles, LoadOptions, ModelChoice, ReadLimits};

use crate::args::{CalibrateArgs, CalibrateConfig, CorrectArgs, DataSetArgs};
use crate::messages::Output;

/// psdcal: calibrate infrared position-sensitive-device (PSD) sensors.
#[derive(Debug, Parser)]
#[command(name = "psdcal", version, after_help = include_str!("../help/main.txt"))]
pub struct Cli {
    /// Print no summary; only errors, warnings and requested data
    #[arg(long, short = 'q', global = true, conflicts_with = "json")]
    pub quiet: bool,
    /// Print the summary as JSON on standard output
    #[arg(long, global = true)]
    pub json: bool,
    /// Largest input file read whole, MiB (default 512; streamed points
    /// files have no limit; docs/formats.md, "Limits")
    #[arg(long, global = true, value_name = "MB", value_parser = clap::value_parser!(u64).range(1..=1_048_576))]
    pub max_input_mb: Option<u64>,
    /// Replace files in an output folder that psdcal did not write there
    #[arg(long, global = true)]
    pub force: bool,
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands (each one's arguments built only when it is invoked).
#[derive(Debug, Clone, PartialEq, Subcommand)]
#[command(defer = true)]
pub enum Command {
    /// Validate a calibration data set and summarise images, points and sensor coverage
    #[command(after_help = include_str!("../help/check.txt"))]
    Check(DataSetArgs),
    /// Calibrate a sensor from images of an LED template (adapted Zhang method + Levenberg-Marquardt)
    #[command(after_help = include_str!("../help/calibrate.txt"))]
    Calibrate(CalibrateArgs),
    /// Calibrate a mounted sensor in situ from emitters at surveyed 3-D positions (its pose in the room too)
    #[command(after_help = include_str!("../help/calibrate_in_situ.txt"))]
    CalibrateInSitu(crate::cmd_calibrate_in_situ::InSituArgs),
    /// Calibrate a room of sensors from a waved wand: every pose and lens, no surveyed emitters (rig.json)
    #[command(after_help = include_str!("../help/calibrate_network.txt"))]
    CalibrateNetwork(psdcal::NetworkRequest),
    /// Simulate a room of sensors, a waved wand, a static frame and test emitters
    #[command(after_help = include_str!("../help/simulate_network.txt"))]
    SimulateNetwork(psdcal::NetworkSimRequest),
    /// Simulate a calibration data set through the whole signal chain
    #[command(after_help = include_str!("../help/simulate.txt"))]
    Simulate(crate::cli_sim::SimulateArgs),
    /// Run the paper's Monte Carlo evaluation (Tables 1-10, Figure 9) next to the paper's numbers
    #[command(after_help = include_str!("../help/study.txt"))]
    Study(crate::cli_sim::StudyArgs),
    /// Simulate, calibrate and compare with the truth in a few seconds (start here)
    #[command(after_help = include_str!("../help/demo.txt"))]
    Demo(crate::cli_sim::DemoArgs),
    /// Estimate the amplifier gains from equal-current records (electrical calibration)
    #[command(after_help = include_str!("../help/gains.txt"))]
    Gains(crate::cmd_gains::GainsArgs),
    /// The PSD's own non-linearity map from a lensless scan (psd_map.json for calibrate --psd-map)
    #[command(after_help = include_str!("../help/psd_map.txt"))]
    PsdMap(crate::cmd_psd_map::PsdMapArgs),
    /// Simulate a lensless raster scan of the PSD (scan.csv for psd-map)
    #[command(after_help = include_str!("../help/psd_map.txt"))]
    SimulateScan(crate::cmd_simulate_scan::SimulateScanArgs),
    /// Correct measured points (or electrode amplitudes) to ideal points with a calibration
    #[command(after_help = include_str!("../help/correct.txt"))]
    Correct(CorrectArgs),
    /// Angles of arrival of measured points (or amplitudes) with their uncertainty
    #[command(after_help = include_str!("../help/aoa.txt"))]
    Aoa(crate::cli_locate::AoaArgs),
    /// Emitter positions on a plane, or from a rig of sensors, with their 3-D covariance
    #[command(after_help = include_str!("../help/locate.txt"))]
    Locate(crate::cli_locate::LocateArgs),
    /// Maps of the AoA and position errors over the sensor area (the paper's Figure 9)
    #[command(after_help = include_str!("../help/map.txt"))]
    Map(crate::cli_locate::MapArgs),
    /// A self-contained HTML report of a calibration with its plots (SVG and PNG)
    #[command(after_help = include_str!("../help/report.txt"))]
    Report(crate::cmd_report::ReportArgs),
    /// Judge estimated positions against a surveyed truth (mean, RMS, 75th/95th percentiles, CE95, SE95, honest error bars)
    #[command(after_help = include_str!("../help/evaluate.txt"))]
    Evaluate(crate::cmd_evaluate::EvaluateArgs),
    /// Simulate a calibrated rig of sensors and emitters at known positions (rig.json, rig_points.csv, truth.csv)
    #[command(after_help = include_str!("../help/simulate-positioning.txt"))]
    SimulatePositioning(crate::cmd_simulate_positioning::PositioningArgs),
    /// Demodulate a raw recording (raw.csv, raw.npy) into signals.csv with a per-record SNR
    #[command(after_help = include_str!("../help/demodulate.txt"))]
    Demodulate(crate::cmd_demodulate::DemodulateArgs),
    /// Angles of arrival per window and LED from raw samples on standard input (live)
    #[command(after_help = include_str!("../help/track.txt"))]
    Track(crate::cmd_track::TrackArgs),
    /// A rig's positions live in the browser: a 3-D page, /stream (Server-Sent Events) and /rig
    Serve(crate::cmd_serve::ServeArgs),
    /// A calibration as an OpenCV, mrcal or ROS camera model (fitted, with its error)
    #[command(after_help = include_str!("../help/export.txt"))]
    Export(crate::cmd_export::ExportArgs),
    /// Two calibrations of one sensor compared in angles over the active area (did it drift?)
    #[command(after_help = include_str!("../help/diff.txt"))]
    Diff(crate::cmd_diff::DiffArgs),
    /// Plan template poses that minimise the predicted angle-of-arrival uncertainty (poses.csv)
    #[command(after_help = include_str!("../help/plan.txt"))]
    Plan(crate::cmd_plan::PlanArgs),
    /// Check the focal length against a square of known size at a known distance (Eq. 44)
    #[command(after_help = include_str!("../help/focal_check.txt"))]
    FocalCheck(crate::cmd_focal_check::FocalCheckArgs),
}

/// What to run.
#[derive(Debug, Clone, PartialEq)]
pub enum Job {
    /// A command run as parsed.
    Plain(Command),
    Study(psdcal::StudyRequest),
    Check(DataSetFiles, LoadOptions),
    Calibrate(CalibrateConfig),
    Correct(CorrectArgs),
    Aoa(crate::cli_locate::AoaArgs),
    Locate(crate::cli_locate::LocateConfig),
    Map(psdcal::MapRequest, Option<PathBuf>),
}

impl Cli {
    /// The bounds of the files read whole (`--max-input-mb`).
    pub fn read_limits(&self) -> ReadLimits {
        self.max_input_mb
            .map_or_else(ReadLimits::default, ReadLimits::from_mib)
    }

    /// The output mode and the job; a combination clap cannot express is a
    /// usage error (exit 2).
    pub fn into_job(self) -> Result<(Output, Job), clap::Error> {
        let limits = self.read_limits();
        let output = if self.json {
            Output::Json
        } else if self.quiet {
            Output::Quiet
        } else {
            Output::Text
        };
        let job = match self.command {
            Command::Check(args) => {
                let (files, load) = args.into_files(None, limits)?;
                Job::Check(files, load)
            }
            Command::Study(args) => Job::Study(args.into_config(self.force)),
            Command::Aoa(args) => {
                crate::cli_locate::json_needs_out("aoa", &args.out, output)?;
                Job::Aoa(args)
            }
            Command::Locate(args) => Job::Locate(args.into_config(output)?),
            Command::Map(args) => {
                let (request, out) = args.into_config(output, limits)?;
                Job::Map(request, out)
            }
            Command::Calibrate(args) => {
                let (files, load) = args.data.into_files(args.gains, limits)?;
                let choice = args
                    .fit
                    .as_ref()
                    .map_or(ModelChoice::HeldOut, |_| ModelChoice::Given);
                let fit = args
                    .fit
                    .unwrap_or_else(|| FitList::of(CalibrationOptions::default().free));
                let options = CalibrationOptions {
                    free: fit.params,
                    choice,
                    fit_gains: fit.gains,
                    fit_aspect: fit.aspect,
                    fixed: args.set,
                    focal_guess: args.focal_guess,
                    cost: args.cost,
                    noise: args.noise,
                    preliminary: if args.no_preliminary {
                        psdcal::Preliminary::Off
                    } else {
                        args.preliminary
                    },
                    normalize: !args.no_normalize,
                    robust: args.robust,
                    uncertainty: args.uncertainty,
                    psd_map: args.psd_map,
                    refine_psd_map: args.refine_psd_map,
                };
                let signals = matches!(files.points, PointSource::Signals(_));
                options.check(signals, files.gains.is_some()).map_err(|m| {
                    Cli::command().error(clap::error::ErrorKind::ArgumentConflict, m)
                })?;
                Job::Calibrate(CalibrateConfig {
                    files,
                    load,
                    out: args.out,
                    residuals: args.residuals,
                    options,
                })
            }
            Command::Correct(args) => {
                crate::cli_locate::json_needs_out("correct", &args.out, output)?;
                Job::Correct(args)
            }
            command => Job::Plain(command),
        };
        Ok((output, job))
    }
}
