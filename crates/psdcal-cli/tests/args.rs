//! Argument parsing of `psdcal check` and `correct` into validated
//! configurations, and usage errors (exit 2).

use clap::{CommandFactory, Parser};
use psdcal::{DataSetFiles, LoadOptions};
use psdcal_cli::args::CorrectArgs;
use psdcal_cli::cli::{Cli, Job, PointSource};
use psdcal_cli::messages::Output;
use psdcal_model::PsdGeometry;

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
        Job::Check(
            DataSetFiles {
                template: "t.csv".into(),
                points: PointSource::Observations("o.csv".into()),
                gains: None,
            },
            LoadOptions {
                geometry: PsdGeometry { lx: 9.0, ly: 9.0 },
                strict: false,
                limits: Default::default(),
            }
        )
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
    let Job::Check(files, load) = job else {
        panic!("expected check")
    };
    assert_eq!(files.points, PointSource::Signals("s.csv".into()));
    assert_eq!(load.geometry, PsdGeometry { lx: 10.0, ly: 8.5 });
    assert!(load.strict);
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
        Job::Correct(CorrectArgs {
            calibration: "c.json".into(),
            points: "p.csv".into(),
            out: Some("o.csv".into()),
        })
    );
}
