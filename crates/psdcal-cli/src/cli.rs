//! Command-line arguments (clap) and the validated configuration they turn
//! into. Nothing here reads files: it only decides what to do.

use std::path::PathBuf;

use clap::{ArgGroup, Args, CommandFactory, Parser, Subcommand};
pub use psdcal::PointSource;
use psdcal::{CalibrationOptions, Param, PsdGeometry, Robust, Uncertainty};
use psdcal_model::UnknownParam;

use crate::choice::{CostArg, NoiseArg, PreliminaryArg};

const MAIN_EXAMPLES: &str = include_str!("../help/main.txt");

const CHECK_EXAMPLES: &str = include_str!("../help/check.txt");

const CALIBRATE_EXAMPLES: &str = include_str!("../help/calibrate.txt");

const CORRECT_EXAMPLES: &str = include_str!("../help/correct.txt");

/// psdcal: calibrate infrared position-sensitive-device (PSD) sensors.
#[derive(Debug, Parser)]
#[command(name = "psdcal", version, after_help = MAIN_EXAMPLES)]
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
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Validate a calibration data set and summarise images, points and sensor coverage
    #[command(after_help = CHECK_EXAMPLES)]
    Check(CheckArgs),
    /// Calibrate a sensor from images of an LED template (adapted Zhang method + Levenberg-Marquardt)
    #[command(after_help = CALIBRATE_EXAMPLES)]
    Calibrate(CalibrateArgs),
    /// Simulate a calibration data set through the whole signal chain
    #[command(after_help = crate::cli_sim::SIMULATE_EXAMPLES)]
    Simulate(crate::cli_sim::SimulateArgs),
    /// Run the paper's Monte Carlo evaluation (Tables 1-10, Figure 9) next to the paper's numbers
    #[command(after_help = crate::cli_sim::STUDY_EXAMPLES)]
    Study(crate::cli_sim::StudyArgs),
    /// Simulate, calibrate and compare with the truth in a few seconds (start here)
    #[command(after_help = crate::cli_sim::DEMO_EXAMPLES)]
    Demo(crate::cli_sim::DemoArgs),
    /// Estimate the amplifier gains from equal-current records (electrical calibration)
    #[command(after_help = crate::cli_gains::GAINS_EXAMPLES)]
    Gains(crate::cli_gains::GainsArgs),
    /// Correct measured points (or electrode amplitudes) to ideal points with a calibration
    #[command(after_help = CORRECT_EXAMPLES)]
    Correct(CorrectArgs),
    /// Angles of arrival of measured points (or amplitudes) with their uncertainty
    #[command(after_help = crate::cli_locate::AOA_EXAMPLES)]
    Aoa(crate::cli_locate::AoaArgs),
    /// Emitter positions on a plane, or from a rig of sensors, with their 3-D covariance
    #[command(after_help = crate::cli_locate::LOCATE_EXAMPLES)]
    Locate(crate::cli_locate::LocateArgs),
    /// Maps of the AoA and position errors over the sensor area (the paper's Figure 9)
    #[command(after_help = crate::cli_locate::MAP_EXAMPLES)]
    Map(crate::cli_locate::MapArgs),
    /// A self-contained HTML report of a calibration with its plots (SVG and PNG)
    #[command(after_help = crate::cli_report::REPORT_EXAMPLES)]
    Report(crate::cli_report::ReportArgs),
    /// Demodulate a raw recording (raw.csv, raw.npy) into signals.csv with a per-record SNR
    #[command(after_help = crate::cmd_demodulate::DEMODULATE_EXAMPLES)]
    Demodulate(crate::cmd_demodulate::DemodulateArgs),
    /// Angles of arrival per window and LED from raw samples on standard input (live)
    #[command(after_help = crate::cmd_track::TRACK_EXAMPLES)]
    Track(crate::cmd_track::TrackArgs),
}

/// Arguments of `psdcal check`.
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("input").required(true).args(["observations", "signals"])))]
pub struct CheckArgs {
    /// Template: led, X_mm, Y_mm[, lines]
    #[arg(long, short = 't', value_name = "FILE")]
    pub template: PathBuf,
    /// Measured impact points: image, led, x_mm, y_mm
    #[arg(long, short = 'o', value_name = "FILE")]
    pub observations: Option<PathBuf>,
    /// Electrode amplitudes instead of impact points: image, led, vx1, vx2, vy1, vy2
    #[arg(long, short = 's', value_name = "FILE")]
    pub signals: Option<PathBuf>,
    /// Active area side along x, mm
    #[arg(long, value_name = "MM", default_value = "9", value_parser = side_mm, allow_negative_numbers = true)]
    pub lx: f64,
    /// Active area side along y, mm
    #[arg(long, value_name = "MM", default_value = "9", value_parser = side_mm, allow_negative_numbers = true)]
    pub ly: f64,
    /// Treat every warning as an error instead of dropping the data
    #[arg(long)]
    pub strict: bool,
}

/// Arguments of `psdcal calibrate`.
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("input").required(true).args(["observations", "signals"])))]
pub struct CalibrateArgs {
    /// Template: led, X_mm, Y_mm[, lines]
    #[arg(long, short = 't', value_name = "FILE")]
    pub template: PathBuf,
    /// Measured impact points: image, led, x_mm, y_mm
    #[arg(long, short = 'o', value_name = "FILE")]
    pub observations: Option<PathBuf>,
    /// Electrode amplitudes instead of impact points: image, led, vx1, vx2, vy1, vy2
    #[arg(long, short = 's', value_name = "FILE")]
    pub signals: Option<PathBuf>,
    /// Where to write calibration.json (atomically)
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Parameters to estimate, comma-separated (the others stay fixed); add
    /// `gains` to self-calibrate the amplifier gains (needs --signals)
    #[arg(long, value_name = "LIST", default_value = "f,cx,cy,k1,k2", value_parser = parse_fit)]
    pub fit: FitList,
    /// Nominal focal length of the lens, mm (narrows the start's search)
    #[arg(long, value_name = "MM", value_parser = positive_mm)]
    pub focal_guess: Option<f64>,
    /// Cost to minimise: template (the paper's template-plane error) or image
    #[arg(long, value_name = "KIND", value_enum, default_value_t = CostArg::Template)]
    pub cost: CostArg,
    /// Noise weighting of the cost: uniform (unweighted, the paper's),
    /// channel-snr (the same SNR on every electrode channel: points near the
    /// electrodes weigh more) or channel-floor (the same absolute noise on
    /// every channel: brighter spots weigh more)
    #[arg(long, value_name = "MODEL", value_enum, default_value_t = NoiseArg::Uniform)]
    pub noise: NoiseArg,
    /// Preliminary distortion correction before the linear stage: auto (line
    /// straightness when the template declares lines, else homography
    /// consistency), straightness, homography, or off
    #[arg(long, value_name = "METHOD", value_enum, default_value_t = PreliminaryArg::Auto)]
    pub preliminary: PreliminaryArg,
    /// Skip the preliminary distortion correction (same as --preliminary off)
    #[arg(long, conflicts_with = "preliminary")]
    pub no_preliminary: bool,
    /// Skip the data normalisation of the homographies
    #[arg(long)]
    pub no_normalize: bool,
    /// Robust loss: huber:SCALE or cauchy:SCALE (SCALE in mm of the cost)
    #[arg(long, value_name = "LOSS:SCALE", value_parser = parse_robust)]
    pub robust: Option<Robust>,
    /// Covariance of the estimate: linear (analytic, the default) or
    /// bootstrap:N[:SEED] (N ≥ 10 refits of images resampled with
    /// replacement; seed 1 by default), where the linear one is not enough
    #[arg(long, value_name = "METHOD", default_value = "linear", value_parser = parse_uncertainty)]
    pub uncertainty: Uncertainty,
    /// Value of a fixed parameter, NAME=VALUE (repeatable), e.g. l1=-1.3058e-3
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_assignment, allow_negative_numbers = true)]
    pub set: Vec<(Param, f64)>,
    /// Channel gains from `psdcal gains` (gains.json), divided out of the
    /// amplitudes and held fixed (needs --signals)
    #[arg(long, value_name = "FILE")]
    pub gains: Option<PathBuf>,
    /// Also write every point's residuals to this CSV
    #[arg(long, value_name = "FILE")]
    pub residuals: Option<PathBuf>,
    /// Active area side along x, mm
    #[arg(long, value_name = "MM", default_value = "9", value_parser = side_mm, allow_negative_numbers = true)]
    pub lx: f64,
    /// Active area side along y, mm
    #[arg(long, value_name = "MM", default_value = "9", value_parser = side_mm, allow_negative_numbers = true)]
    pub ly: f64,
    /// Treat every data warning as an error instead of dropping the data
    #[arg(long)]
    pub strict: bool,
}

/// The parameters named by `--fit`, and whether `gains` was named.
#[derive(Debug, Clone, PartialEq)]
pub struct FitList(pub Vec<Param>, pub bool);

/// Arguments of `psdcal correct`.
#[derive(Debug, Args)]
pub struct CorrectArgs {
    /// Calibration written by psdcal (calibration.json)
    #[arg(long, short = 'c', value_name = "FILE")]
    pub calibration: PathBuf,
    /// Points to correct: x_mm, y_mm (or vx1, vx2, vy1, vy2), other columns kept
    #[arg(long, short = 'p', value_name = "FILE")]
    pub points: PathBuf,
    /// Output CSV (written atomically); standard output when absent
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// How results are shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Output {
    /// Human-readable summary on standard output.
    Text,
    /// No summary.
    Quiet,
    /// JSON on standard output.
    Json,
}

/// Validated configuration of `psdcal check`.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckConfig {
    pub template: PathBuf,
    pub points: PointSource,
    pub geometry: PsdGeometry,
    pub strict: bool,
}

/// Validated configuration of `psdcal correct`.
#[derive(Debug, Clone, PartialEq)]
pub struct CorrectConfig {
    pub calibration: PathBuf,
    pub points: PathBuf,
    pub out: Option<PathBuf>,
}

/// Validated configuration of `psdcal calibrate`.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrateConfig {
    pub template: PathBuf,
    pub points: PointSource,
    pub geometry: PsdGeometry,
    pub strict: bool,
    pub out: PathBuf,
    pub residuals: Option<PathBuf>,
    pub gains_file: Option<PathBuf>,
    pub options: CalibrationOptions,
}

/// What to run.
#[derive(Debug, Clone, PartialEq)]
pub enum Job {
    Gains(crate::cli_gains::GainsArgs),
    Simulate(crate::cli_sim::SimulateArgs),
    Study(crate::cli_sim::StudyConfig),
    Demo(crate::cli_sim::DemoArgs),
    Check(CheckConfig),
    Calibrate(CalibrateConfig),
    Correct(CorrectConfig),
    Aoa(crate::cli_locate::AoaConfig),
    Locate(crate::cli_locate::LocateConfig),
    Map(crate::cli_locate::MapConfig),
    Report(crate::cli_report::ReportConfig),
    Demodulate(crate::cmd_demodulate::DemodulateArgs),
    Track(crate::cmd_track::TrackArgs),
}

impl Cli {
    /// The output mode and the job; a combination clap cannot express is a
    /// usage error (exit 2).
    pub fn into_job(self) -> Result<(Output, Job), clap::Error> {
        let output = if self.json {
            Output::Json
        } else if self.quiet {
            Output::Quiet
        } else {
            Output::Text
        };
        let job = match self.command {
            Command::Check(args) => {
                let points = point_source(args.observations, args.signals)?;
                Job::Check(CheckConfig {
                    template: args.template,
                    points,
                    geometry: PsdGeometry {
                        lx: args.lx,
                        ly: args.ly,
                    },
                    strict: args.strict,
                })
            }
            Command::Gains(args) => Job::Gains(args),
            Command::Simulate(args) => Job::Simulate(args),
            Command::Study(args) => Job::Study(args.into_config()),
            Command::Demo(args) => Job::Demo(args),
            Command::Aoa(args) => Job::Aoa(args.into_config(output)?),
            Command::Locate(args) => Job::Locate(args.into_config(output)?),
            Command::Map(args) => Job::Map(args.into_config(output)?),
            Command::Report(args) => Job::Report(args.into_config()),
            Command::Demodulate(args) => Job::Demodulate(args),
            Command::Track(args) => Job::Track(args),
            Command::Calibrate(args) => {
                let points = point_source(args.observations, args.signals)?;
                let FitList(free, fit_gains) = args.fit;
                if args.gains.is_some() && (fit_gains || !matches!(points, PointSource::Signals(_)))
                {
                    return Err(Cli::command().error(
                        clap::error::ErrorKind::ArgumentConflict,
                        "--gains FILE holds known gains fixed: it needs --signals and excludes 'gains' in --fit",
                    ));
                }
                if fit_gains && !matches!(points, PointSource::Signals(_)) {
                    return Err(Cli::command().error(
                        clap::error::ErrorKind::ArgumentConflict,
                        "--fit ...,gains needs the electrode amplitudes: give --signals signals.csv",
                    ));
                }
                for (p, _) in &args.set {
                    if free.contains(p) {
                        return Err(Cli::command().error(
                            clap::error::ErrorKind::ArgumentConflict,
                            format!("--set {p}=... fixes {p}, but --fit also frees it; drop one of them"),
                        ));
                    }
                }
                Job::Calibrate(CalibrateConfig {
                    template: args.template,
                    points,
                    geometry: PsdGeometry {
                        lx: args.lx,
                        ly: args.ly,
                    },
                    strict: args.strict,
                    out: args.out,
                    residuals: args.residuals,
                    gains_file: args.gains,
                    options: CalibrationOptions {
                        free,
                        fit_gains,
                        fixed: args.set,
                        focal_guess: args.focal_guess,
                        cost: args.cost.into(),
                        noise: args.noise.into(),
                        preliminary: if args.no_preliminary {
                            psdcal::Preliminary::Off
                        } else {
                            args.preliminary.into()
                        },
                        normalize: !args.no_normalize,
                        robust: args.robust,
                        uncertainty: args.uncertainty,
                    },
                })
            }
            Command::Correct(args) => {
                if output == Output::Json && args.out.is_none() {
                    return Err(Cli::command().error(
                        clap::error::ErrorKind::MissingRequiredArgument,
                        "'correct --json' needs '--out FILE': standard output carries the JSON \
                         summary, so the corrected table must go to a file",
                    ));
                }
                Job::Correct(CorrectConfig {
                    calibration: args.calibration,
                    points: args.points,
                    out: args.out,
                })
            }
        };
        Ok((output, job))
    }
}

/// `--fit`: comma-separated parameter names, each at most once.
fn parse_fit(text: &str) -> Result<FitList, String> {
    let mut out: Vec<Param> = Vec::new();
    let mut gains = false;
    for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        if name.eq_ignore_ascii_case("gains") {
            if gains {
                return Err("'gains' is listed twice".into());
            }
            gains = true;
            continue;
        }
        let p: Param = name.parse().map_err(|e: UnknownParam| e.to_string())?;
        if out.contains(&p) {
            return Err(format!("'{p}' is listed twice"));
        }
        out.push(p);
    }
    if out.is_empty() {
        return Err("expected at least one parameter, e.g. f,cx,cy,k1,k2".into());
    }
    Ok(FitList(out, gains))
}

/// `--robust huber:0.1` or `cauchy:0.1`.
fn parse_robust(text: &str) -> Result<Robust, String> {
    let (kind, scale) = text
        .split_once(':')
        .ok_or_else(|| format!("expected LOSS:SCALE such as huber:0.1, found '{text}'"))?;
    let scale = positive_mm(scale)?;
    match kind.trim().to_ascii_lowercase().as_str() {
        "huber" => Ok(Robust::Huber { scale }),
        "cauchy" => Ok(Robust::Cauchy { scale }),
        other => Err(format!("unknown loss '{other}' (expected huber or cauchy)")),
    }
}

/// `--uncertainty linear`, `bootstrap:N` or `bootstrap:N:SEED`.
fn parse_uncertainty(text: &str) -> Result<Uncertainty, String> {
    let mut parts = text.split(':');
    match parts
        .next()
        .map(|p| p.trim().to_ascii_lowercase())
        .as_deref()
    {
        Some("linear") if parts.next().is_none() => Ok(Uncertainty::Linear),
        Some("bootstrap") => {
            let number = |part: Option<&str>, what: &str| -> Result<Option<u64>, String> {
                part.map(|p| {
                    p.trim()
                        .parse::<u64>()
                        .map_err(|_| format!("expected a whole number for the {what}, found '{p}'"))
                })
                .transpose()
            };
            let resamples = number(parts.next(), "resamples")?
                .ok_or("expected bootstrap:N, e.g. bootstrap:200")?;
            if resamples < 10 {
                return Err(format!(
                    "the bootstrap needs at least 10 resamples, not {resamples}"
                ));
            }
            let seed = number(parts.next(), "seed")?.unwrap_or(1);
            if parts.next().is_some() {
                return Err(format!("expected bootstrap:N[:SEED], found '{text}'"));
            }
            Ok(Uncertainty::Bootstrap {
                resamples: resamples as usize,
                seed,
            })
        }
        _ => Err(format!(
            "expected linear or bootstrap:N[:SEED], found '{text}'"
        )),
    }
}

/// `--set NAME=VALUE`.
fn parse_assignment(text: &str) -> Result<(Param, f64), String> {
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE such as l1=-1.3e-3, found '{text}'"))?;
    let p: Param = name.parse().map_err(|e: UnknownParam| e.to_string())?;
    match value.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok((p, v)),
        _ => Err(format!("expected a finite number for {p}, found '{value}'")),
    }
}

/// Where a data set's points come from: exactly one of `--observations`
/// and `--signals` (clap's group makes one required; this refuses both).
fn point_source(
    observations: Option<PathBuf>,
    signals: Option<PathBuf>,
) -> Result<PointSource, clap::Error> {
    match (observations, signals) {
        (Some(path), None) => Ok(PointSource::Observations(path)),
        (None, Some(path)) => Ok(PointSource::Signals(path)),
        _ => Err(Cli::command().error(
            clap::error::ErrorKind::ArgumentConflict,
            "give exactly one of --observations and --signals",
        )),
    }
}

/// The longest length an option accepts, mm (1 000 km): beyond it results
/// overflow or mean a unit error.
pub(crate) const MAX_LENGTH_MM: f64 = 1e9;
/// The largest active-area side, mm.
pub(crate) const MAX_SIDE_MM: f64 = 1000.0;

/// A positive, finite length in mm, at most [`MAX_LENGTH_MM`].
pub(crate) fn positive_mm(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= MAX_LENGTH_MM => Ok(v),
        _ => Err(format!(
            "expected a positive length in mm up to 1e9, found '{text}'"
        )),
    }
}

/// An active-area side: a positive length in mm, at most [`MAX_SIDE_MM`].
pub(crate) fn side_mm(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= MAX_SIDE_MM => Ok(v),
        _ => Err(format!(
            "expected the side of the active area, a positive length in mm up to 1000, found \
             '{text}'"
        )),
    }
}
