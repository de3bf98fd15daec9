//! Command-line arguments (clap) and the validated configuration they turn
//! into. Nothing here reads files: it only decides what to do.

use std::path::PathBuf;

use clap::{ArgGroup, Args, CommandFactory, Parser, Subcommand};
use psdcal_model::PsdGeometry;

const MAIN_EXAMPLES: &str = "\
Examples:
  psdcal check --template template.csv --observations observations.csv
  psdcal correct --calibration calibration.json --points points.csv --out ideal.csv

Exit codes: 0 success, 1 failure (one 'error:' line on stderr), 2 usage error.";

const CHECK_EXAMPLES: &str = "\
Example:
  psdcal check --template data/example/template.csv \\
               --observations data/example/observations.csv

  validates the data set and prints the number of LEDs, images and points, a
  table of the points of each image with their x and y ranges, what was
  dropped and why, and how much of the sensor the points cover (a 10 x 10 grid
  over the active area). With electrode amplitudes instead of impact points:

  psdcal check -t template.csv --signals signals.csv --lx 9 --ly 9 --strict

Files:
  template.csv      led, X_mm, Y_mm[, lines]   (lines: ';'-separated group labels)
  observations.csv  image, led, x_mm, y_mm
  signals.csv       image, led, vx1, vx2, vy1, vy2
Columns are found by name; '#' lines and blank lines are ignored.";

const CORRECT_EXAMPLES: &str = "\
Example:
  psdcal correct --calibration calibration.json --points points.csv --out ideal.csv

  reads points.csv (columns x_mm, y_mm, or vx1, vx2, vy1, vy2, plus any
  others) and writes every input column unchanged followed by x_ideal_mm,
  y_ideal_mm (and, for amplitudes, the measured x_mm, y_mm first, computed on
  the calibration's sensor size with its channel gains divided out). Without
  --out the table goes to standard output:

  psdcal correct -c calibration.json -p points.csv > ideal.csv";

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
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Validate a calibration data set and summarise images, points and sensor coverage
    #[command(after_help = CHECK_EXAMPLES)]
    Check(CheckArgs),
    /// Correct measured points (or electrode amplitudes) to ideal points with a calibration
    #[command(after_help = CORRECT_EXAMPLES)]
    Correct(CorrectArgs),
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
    #[arg(long, value_name = "MM", default_value = "9", value_parser = positive_mm, allow_negative_numbers = true)]
    pub lx: f64,
    /// Active area side along y, mm
    #[arg(long, value_name = "MM", default_value = "9", value_parser = positive_mm, allow_negative_numbers = true)]
    pub ly: f64,
    /// Treat every warning as an error instead of dropping the data
    #[arg(long)]
    pub strict: bool,
}

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

/// Where `check` takes its points from.
#[derive(Debug, Clone, PartialEq)]
pub enum PointSource {
    /// observations.csv.
    Observations(PathBuf),
    /// signals.csv.
    Signals(PathBuf),
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

/// What to run.
#[derive(Debug, Clone, PartialEq)]
pub enum Job {
    Check(CheckConfig),
    Correct(CorrectConfig),
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
                let points = match (args.observations, args.signals) {
                    (Some(path), None) => PointSource::Observations(path),
                    (None, Some(path)) => PointSource::Signals(path),
                    _ => {
                        return Err(Cli::command().error(
                            clap::error::ErrorKind::ArgumentConflict,
                            "give exactly one of --observations and --signals",
                        ))
                    }
                };
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

/// A positive, finite length in mm.
fn positive_mm(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("expected a positive length in mm, found '{text}'")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<(Output, Job), clap::Error> {
        Cli::try_parse_from(args)?.into_job()
    }

    #[test]
    fn the_command_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn check_with_observations_and_defaults() {
        let (output, job) = parse(&["psdcal", "check", "-t", "t.csv", "-o", "o.csv"]).unwrap();
        assert_eq!(output, Output::Text);
        assert_eq!(
            job,
            Job::Check(CheckConfig {
                template: "t.csv".into(),
                points: PointSource::Observations("o.csv".into()),
                geometry: PsdGeometry { lx: 9.0, ly: 9.0 },
                strict: false,
            })
        );
    }

    #[test]
    fn check_with_signals_geometry_strict_and_json_after_the_subcommand() {
        let (output, job) = parse(&[
            "psdcal",
            "check",
            "--template",
            "t.csv",
            "--signals",
            "s.csv",
            "--lx",
            "10",
            "--ly",
            "8.5",
            "--strict",
            "--json",
        ])
        .unwrap();
        assert_eq!(output, Output::Json);
        let Job::Check(config) = job else {
            panic!("expected check")
        };
        assert_eq!(config.points, PointSource::Signals("s.csv".into()));
        assert_eq!(config.geometry, PsdGeometry { lx: 10.0, ly: 8.5 });
        assert!(config.strict);
    }

    #[test]
    fn usage_errors() {
        use clap::error::ErrorKind;
        let kind = |args: &[&str]| parse(args).unwrap_err().kind();
        assert_eq!(
            kind(&["psdcal", "check", "-t", "t.csv"]),
            ErrorKind::MissingRequiredArgument
        );
        assert_eq!(
            kind(&["psdcal", "check", "-t", "t", "-o", "o", "-s", "s"]),
            ErrorKind::ArgumentConflict
        );
        assert_eq!(
            kind(&["psdcal", "check", "-t", "t", "-o", "o", "--lx", "-1"]),
            ErrorKind::ValueValidation
        );
        assert_eq!(
            kind(&["psdcal", "check", "-t", "t", "-o", "o", "--ly", "nan"]),
            ErrorKind::ValueValidation
        );
        assert_eq!(
            kind(&["psdcal", "--quiet", "--json", "check", "-t", "t", "-o", "o"]),
            ErrorKind::ArgumentConflict
        );
        assert_eq!(
            kind(&["psdcal", "--json", "correct", "-c", "c", "-p", "p"]),
            ErrorKind::MissingRequiredArgument
        );
        assert_eq!(
            kind(&["psdcal", "frobnicate"]),
            ErrorKind::InvalidSubcommand
        );
    }

    #[test]
    fn correct_config() {
        let (output, job) = parse(&[
            "psdcal", "-q", "correct", "-c", "c.json", "-p", "p.csv", "--out", "o.csv",
        ])
        .unwrap();
        assert_eq!(output, Output::Quiet);
        assert_eq!(
            job,
            Job::Correct(CorrectConfig {
                calibration: "c.json".into(),
                points: "p.csv".into(),
                out: Some("o.csv".into()),
            })
        );
    }
}
