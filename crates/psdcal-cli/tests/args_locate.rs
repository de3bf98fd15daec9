//! Argument parsing of `psdcal aoa`, `locate` and `map` into validated
//! configurations, and their usage errors.

use clap::Parser;
use psdcal::Plane;
use psdcal_cli::cli::{Cli, Job};
use psdcal_cli::cli_locate::{AoaArgs, LocateTarget, MapModel, MapSource};
use psdcal_cli::messages::Output;
use psdcal_model::Param;

fn parse(args: &[&str]) -> Result<(Output, Job), clap::Error> {
    Cli::try_parse_from(args)?.into_job()
}

#[test]
fn aoa_config() {
    let (_, job) = parse(&[
        "psdcal",
        "aoa",
        "-c",
        "c.json",
        "-p",
        "p.csv",
        "--point-sigma",
        "0.001",
    ])
    .unwrap();
    assert_eq!(
        job,
        Job::Aoa(AoaArgs {
            calibration: "c.json".into(),
            points: "p.csv".into(),
            out: None,
            point_sigma: Some(0.001),
        })
    );
}

#[test]
fn locate_targets() {
    let (_, job) = parse(&[
        "psdcal",
        "locate",
        "-c",
        "c",
        "-p",
        "p",
        "--distance",
        "5000",
    ])
    .unwrap();
    let Job::Locate(config) = job else { panic!() };
    assert_eq!(
        config.target,
        LocateTarget::Plane {
            calibration: "c".into(),
            plane: Plane::parallel(5000.0).unwrap()
        }
    );
    assert_eq!(config.options.point_sigma_mm, 0.0);
    let (_, job) = parse(&[
        "psdcal",
        "locate",
        "-c",
        "c",
        "-p",
        "p",
        "--plane",
        "0,-2,0,-2500",
    ])
    .unwrap();
    let Job::Locate(config) = job else { panic!() };
    // -2y = -2500 is the plane y = 1250 mm.
    let LocateTarget::Plane { plane, .. } = config.target else {
        panic!()
    };
    assert_eq!(plane.offset_mm(), 1250.0);
    let (_, job) = parse(&[
        "psdcal",
        "locate",
        "--rig",
        "r.json",
        "-p",
        "p",
        "--unweighted",
        "--point-sigma",
        "0",
    ])
    .unwrap();
    let Job::Locate(config) = job else { panic!() };
    assert_eq!(config.target, LocateTarget::Rig("r.json".into()));
    assert!(!config.options.weight_rays);
    assert!(config.point_sigma_given);
}

#[test]
fn map_config() {
    let (_, job) = parse(&[
        "psdcal",
        "map",
        "--lens",
        "1",
        "--error",
        "f=0.05,cx=-0.02",
        "--error",
        "k1=1e-4",
        "--paper",
    ])
    .unwrap();
    let Job::Map(config, _) = job else { panic!() };
    assert_eq!(config.model, MapModel::PaperLens(1));
    assert_eq!(
        config.source,
        MapSource::Errors(vec![
            (Param::F, 0.05),
            (Param::Cx, -0.02),
            (Param::K1, 1e-4)
        ])
    );
    assert_eq!((config.grid, config.distance_mm), (41, 5000.0));
    let (_, job) = parse(&[
        "psdcal",
        "map",
        "-c",
        "c.json",
        "--k-sigma",
        "2",
        "--grid",
        "5",
    ])
    .unwrap();
    let Job::Map(config, _) = job else { panic!() };
    assert_eq!(config.source, MapSource::KSigma(2.0));
}

#[test]
fn usage_errors() {
    use clap::error::ErrorKind;
    let kind = |args: &[&str]| parse(args).unwrap_err().kind();
    assert_eq!(
        kind(&["psdcal", "aoa", "-c", "c"]),
        ErrorKind::MissingRequiredArgument
    );
    assert_eq!(
        kind(&["psdcal", "aoa", "-c", "c", "-p", "p", "--point-sigma", "-1"]),
        ErrorKind::ValueValidation
    );
    assert_eq!(
        kind(&["psdcal", "--json", "aoa", "-c", "c", "-p", "p"]),
        ErrorKind::MissingRequiredArgument
    );
    assert_eq!(
        kind(&["psdcal", "locate", "-c", "c", "-p", "p"]),
        ErrorKind::MissingRequiredArgument
    );
    assert_eq!(
        kind(&[
            "psdcal",
            "locate",
            "-c",
            "c",
            "-p",
            "p",
            "--distance",
            "1",
            "--rig",
            "r"
        ]),
        ErrorKind::ArgumentConflict
    );
    assert_eq!(
        kind(&["psdcal", "locate", "-p", "p", "--distance", "1"]),
        ErrorKind::MissingRequiredArgument
    );
    assert_eq!(
        kind(&["psdcal", "locate", "-c", "c", "-p", "p", "--distance", "0"]),
        ErrorKind::ValueValidation
    );
    assert_eq!(
        kind(&["psdcal", "locate", "-c", "c", "-p", "p", "--plane", "0,0,0,5"]),
        ErrorKind::ValueValidation
    );
    assert_eq!(
        kind(&["psdcal", "locate", "-c", "c", "-p", "p", "--plane", "0,0,1,0"]),
        ErrorKind::ValueValidation
    );
    assert_eq!(
        kind(&[
            "psdcal",
            "locate",
            "-c",
            "c",
            "-p",
            "p",
            "--distance",
            "5",
            "--unweighted"
        ]),
        ErrorKind::ArgumentConflict
    );
    assert_eq!(
        kind(&["psdcal", "map", "--lens", "1"]),
        ErrorKind::MissingRequiredArgument
    );
    assert_eq!(
        kind(&["psdcal", "map", "--lens", "3", "--error", "f=1"]),
        ErrorKind::InvalidValue
    );
    assert_eq!(
        kind(&["psdcal", "map", "--lens", "1", "--error", "zoom=1"]),
        ErrorKind::ValueValidation
    );
    assert_eq!(
        kind(&["psdcal", "map", "--lens", "1", "--k-sigma", "2"]),
        ErrorKind::ArgumentConflict
    );
    assert_eq!(
        kind(&["psdcal", "map", "--lens", "1", "--error", "f=1", "--error", "f=2"]),
        ErrorKind::ValueValidation
    );
    assert_eq!(
        kind(&["psdcal", "map", "--lens", "1", "--error", "f=1", "--grid", "1"]),
        ErrorKind::ValueValidation
    );
}
