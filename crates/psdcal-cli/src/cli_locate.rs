//! Arguments (clap) and validated configurations of `psdcal aoa`,
//! `psdcal locate` and `psdcal map`. Nothing here reads files.

use std::path::PathBuf;

use clap::{ArgGroup, Args, CommandFactory};
use nalgebra::Vector3;
use psdcal::{LocateOptions, Param, Plane, MAX_GRID};
pub use psdcal::{LocateTarget, MapModel, MapSource};
use psdcal_model::UnknownParam;

use crate::choice::LensArg;
use crate::cli::{positive_mm, Cli, Output};

pub const AOA_EXAMPLES: &str = "\
Example:
  psdcal aoa --calibration calibration.json --points points.csv --point-sigma 0.001 --out aoa.csv

  reads points.csv (x_mm, y_mm, or vx1, vx2, vy1, vy2, plus any other columns,
  which are kept) and adds, per row: x_ideal_mm, y_ideal_mm (the corrected
  point), alpha_x_deg, alpha_y_deg (MODEL.md §5: atan of the normalised ray),
  ray_x, ray_y, ray_z (unit ray towards the emitter, sensor frame),
  sigma_alpha_x_deg, sigma_alpha_y_deg, rho_alpha_xy (1-σ uncertainty and
  correlation), sigma_alpha_x_cal_deg, sigma_alpha_y_cal_deg (the
  calibration's covariance alone) and, with --point-sigma, the point noise's
  part sigma_alpha_x_point_deg, sigma_alpha_y_point_deg; then status.
  Amplitude rows first get x_mm, y_mm (MODEL.md §1, the calibration's gains
  divided out).

Status: ok | off_active_area (answered; the model was not fitted there) |
  outside_valid_region, no_light, non_finite_input (no answer: empty values).
  A summary line counts them; the batch never stops for one row.";

pub const LOCATE_EXAMPLES: &str = "\
Examples:
  psdcal locate -c calibration.json -p points.csv --distance 5000 --out positions.csv

  emitters on the plane parallel to the sensor 5 m in front of it:
  x = S tan(alpha_x), y = S tan(alpha_y), z = S (sensor frame, mm).

  psdcal locate -c calibration.json -p points.csv --plane 0,-1,0,2500 --out floor.csv

  emitters on the plane n.P = d given in the sensor frame (here the floor
  2.5 m below a sensor whose y axis points up): NX,NY,NZ,D_MM.

  psdcal locate --rig rig.json --points rig_points.csv --point-sigma 0.001 --out emitters.csv

  emitters seen by two or more sensors of a rig (README 'Rig files'): rows
  emitter, sensor, x_mm, y_mm (or amplitudes); one output row per emitter, in
  the world frame, by least-squares intersection of the rays weighted by their
  covariances.

Columns added, F = sensor (plane: input columns kept, then alpha_x_deg,
  alpha_y_deg, x_F_mm, y_F_mm, z_F_mm, range_mm) or F = world (rig: emitter,
  sensors, x_F_mm, y_F_mm, z_F_mm), then sigma_x_F_mm, sigma_y_F_mm,
  sigma_z_F_mm, cov_xy_F_mm2, cov_xz_F_mm2, cov_yz_F_mm2, sigma_position_mm
  (sqrt of the trace), (rig) max_miss_mm, ray_angle_deg, and status. The
  covariance is the calibration's (and, with --point-sigma, the
  measurement's), linearised.

Status: ok | off_active_area, grazing_plane, nearly_parallel_rays (answered,
  with care) | outside_valid_region, parallel_to_plane, points_away_from_plane,
  too_few_sensors, parallel_rays, behind_sensor, no_shared_view, no_light
  (no answer: empty values).";

pub const MAP_EXAMPLES: &str = "\
Examples:
  psdcal map --lens 1 --error f=0.05 --error cx=0.02,cy=0.02 --error k1=1e-4 --out map_lens1.csv

  the paper's Figure 9 for given parameter errors (e.g. |mean - ideal| + 2 std):
  at every point of a 41 x 41 grid over the 9 x 9 mm active area, the AoA
  error |alpha(theta + d) - alpha(theta)| with the full model and the position
  error on the plane parallel to the sensor at --distance (default 5000 mm).

  psdcal map --calibration calibration.json --k-sigma 2 --grid 61 --out map.csv

  the same from a calibration's covariance: k times the propagated sigma.

Columns: x_mm, y_mm, alpha_x_deg, alpha_y_deg, aoa_error_x_deg,
  aoa_error_y_deg, aoa_error_deg (angle between the rays, or k sqrt(sx^2 + sy^2)),
  position_error_x_mm, position_error_y_mm, position_error_mm, with --paper also
  paper_aoa_error_x_deg, paper_aoa_error_y_deg (the small-angle form P42),
  status (ok, or why a grid point has no values, e.g. outside_valid_region).";

/// Arguments of `psdcal aoa`.
#[derive(Debug, Args)]
pub struct AoaArgs {
    /// Calibration written by psdcal (calibration.json)
    #[arg(long, short = 'c', value_name = "FILE")]
    pub calibration: PathBuf,
    /// Points: x_mm, y_mm (or vx1, vx2, vy1, vy2), other columns kept
    #[arg(long, short = 'p', value_name = "FILE")]
    pub points: PathBuf,
    /// Output CSV (written atomically); standard output when absent
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Standard deviation of the measured point per coordinate, mm (adds the measurement noise's part)
    #[arg(long, value_name = "MM", value_parser = non_negative_mm, allow_negative_numbers = true)]
    pub point_sigma: Option<f64>,
}

/// Arguments of `psdcal locate`.
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("target").required(true).args(["distance", "plane", "rig"])))]
pub struct LocateArgs {
    /// Calibration written by psdcal (with --distance or --plane)
    #[arg(
        long,
        short = 'c',
        value_name = "FILE",
        required_unless_present = "rig",
        conflicts_with = "rig"
    )]
    pub calibration: Option<PathBuf>,
    /// Points: x_mm, y_mm or amplitudes (with --rig: emitter, sensor, x_mm, y_mm or amplitudes)
    #[arg(long, short = 'p', value_name = "FILE")]
    pub points: PathBuf,
    /// Distance S of a plane parallel to the sensor, mm
    #[arg(long, value_name = "MM", value_parser = positive_mm, allow_negative_numbers = true)]
    pub distance: Option<f64>,
    /// Plane n.P = d in the sensor frame: NX,NY,NZ,D (D in mm, not 0)
    #[arg(long, value_name = "NX,NY,NZ,D", value_parser = parse_plane, allow_hyphen_values = true)]
    pub plane: Option<PlaneSpec>,
    /// Rig file: sensors with calibrations and poses in a world frame (README 'Rig files')
    #[arg(long, value_name = "FILE")]
    pub rig: Option<PathBuf>,
    /// Output CSV (written atomically); standard output when absent
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Standard deviation of the measured point per coordinate, mm
    #[arg(long, value_name = "MM", value_parser = non_negative_mm, allow_negative_numbers = true)]
    pub point_sigma: Option<f64>,
    /// Flag a ray meeting the plane at less than this angle, degrees
    #[arg(long, value_name = "DEG", default_value = "10", value_parser = angle_deg, allow_negative_numbers = true)]
    pub grazing_warning: f64,
    /// Flag rays whose largest mutual angle is below this, degrees
    #[arg(long, value_name = "DEG", default_value = "5", value_parser = angle_deg, allow_negative_numbers = true)]
    pub parallel_warning: f64,
    /// Intersect rig rays unweighted instead of by their inverse covariances
    #[arg(long)]
    pub unweighted: bool,
}

/// Arguments of `psdcal map`.
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("model").required(true).args(["calibration", "lens"])))]
#[command(group(ArgGroup::new("source").required(true).args(["errors", "k_sigma"])))]
pub struct MapArgs {
    /// Calibration written by psdcal (its model, sensor size and covariance)
    #[arg(long, short = 'c', value_name = "FILE")]
    pub calibration: Option<PathBuf>,
    /// The paper's simulated lens instead of a calibration: 1 (f = 25 mm) or 2 (f = 8 mm), 9 x 9 mm PSD
    #[arg(long, value_name = "N", value_enum)]
    pub lens: Option<LensArg>,
    /// Parameter error NAME=VALUE (repeatable or comma-separated), e.g. f=0.05,cx=0.02,k1=1e-4
    #[arg(long = "error", value_name = "NAME=VALUE", value_parser = parse_error_list, allow_hyphen_values = true)]
    pub errors: Vec<Vec<(Param, f64)>>,
    /// Use the calibration's covariance at K standard deviations instead of --error
    #[arg(long, value_name = "K", value_parser = positive_number, allow_negative_numbers = true)]
    pub k_sigma: Option<f64>,
    /// Distance S of the plane parallel to the sensor, mm
    #[arg(long, value_name = "MM", default_value = "5000", value_parser = positive_mm, allow_negative_numbers = true)]
    pub distance: f64,
    /// Grid points per side over the active area
    #[arg(long, value_name = "N", default_value = "41", value_parser = grid_size, allow_negative_numbers = true)]
    pub grid: usize,
    /// Add the paper's small-angle form (P42) for comparison (with --error)
    #[arg(long)]
    pub paper: bool,
    /// Output CSV (written atomically); standard output when absent
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// A plane `n·P = d` as given on the command line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneSpec {
    pub normal: Vector3<f64>,
    pub offset_mm: f64,
}

/// Validated configuration of `psdcal aoa`.
#[derive(Debug, Clone, PartialEq)]
pub struct AoaConfig {
    pub calibration: PathBuf,
    pub points: PathBuf,
    pub out: Option<PathBuf>,
    pub point_sigma_mm: Option<f64>,
}

/// Validated configuration of `psdcal locate`.
#[derive(Debug, Clone, PartialEq)]
pub struct LocateConfig {
    pub target: LocateTarget,
    pub points: PathBuf,
    pub out: Option<PathBuf>,
    pub options: LocateOptions,
    pub point_sigma_given: bool,
}

/// Validated configuration of `psdcal map`.
#[derive(Debug, Clone, PartialEq)]
pub struct MapConfig {
    pub model: MapModel,
    pub source: MapSource,
    pub distance_mm: f64,
    pub grid: usize,
    pub paper: bool,
    pub out: Option<PathBuf>,
}

fn usage(kind: clap::error::ErrorKind, message: impl std::fmt::Display) -> clap::Error {
    Cli::command().error(kind, message)
}

fn json_needs_out(command: &str, out: &Option<PathBuf>, output: Output) -> Result<(), clap::Error> {
    if output == Output::Json && out.is_none() {
        return Err(usage(
            clap::error::ErrorKind::MissingRequiredArgument,
            format!(
                "'{command} --json' needs '--out FILE': standard output carries the JSON \
                 summary, so the table must go to a file"
            ),
        ));
    }
    Ok(())
}

impl AoaArgs {
    pub fn into_config(self, output: Output) -> Result<AoaConfig, clap::Error> {
        json_needs_out("aoa", &self.out, output)?;
        Ok(AoaConfig {
            calibration: self.calibration,
            points: self.points,
            out: self.out,
            point_sigma_mm: self.point_sigma,
        })
    }
}

impl LocateArgs {
    pub fn into_config(self, output: Output) -> Result<LocateConfig, clap::Error> {
        json_needs_out("locate", &self.out, output)?;
        let conflict = |m: &str| usage(clap::error::ErrorKind::ArgumentConflict, m);
        if self.unweighted && self.rig.is_none() {
            return Err(conflict("--unweighted applies to --rig only"));
        }
        let target = match (self.distance, self.plane, self.rig, self.calibration) {
            (Some(s), None, None, Some(calibration)) => LocateTarget::Plane {
                calibration,
                plane: Plane::parallel(s).map_err(|e| conflict(&e.to_string()))?,
            },
            (None, Some(p), None, Some(calibration)) => LocateTarget::Plane {
                calibration,
                plane: Plane::new(p.normal, p.offset_mm).map_err(|e| conflict(&e.to_string()))?,
            },
            (None, None, Some(rig), None) => LocateTarget::Rig(rig),
            _ => {
                return Err(conflict(
                    "give exactly one of --distance, --plane (both with --calibration) and --rig",
                ))
            }
        };
        Ok(LocateConfig {
            target,
            points: self.points,
            out: self.out,
            options: LocateOptions {
                point_sigma_mm: self.point_sigma.unwrap_or(0.0),
                grazing_warning_rad: self.grazing_warning.to_radians(),
                ray_angle_warning_rad: self.parallel_warning.to_radians(),
                weight_rays: !self.unweighted,
            },
            point_sigma_given: self.point_sigma.is_some(),
        })
    }
}

impl MapArgs {
    pub fn into_config(self, output: Output) -> Result<MapConfig, clap::Error> {
        json_needs_out("map", &self.out, output)?;
        let conflict = |m: &str| usage(clap::error::ErrorKind::ArgumentConflict, m);
        if self.k_sigma.is_some() && self.calibration.is_none() {
            return Err(conflict("--k-sigma needs --calibration (its covariance)"));
        }
        if self.paper && self.k_sigma.is_some() {
            return Err(conflict(
                "--paper needs parameter errors (--error), not --k-sigma",
            ));
        }
        let model = match (self.calibration, self.lens) {
            (Some(path), None) => MapModel::Calibration(path),
            (None, Some(lens)) => MapModel::PaperLens(if lens == LensArg::One { 1 } else { 2 }),
            _ => {
                return Err(usage(
                    clap::error::ErrorKind::ArgumentConflict,
                    "give exactly one of --calibration and --lens",
                ))
            }
        };
        let errors: Vec<(Param, f64)> = self.errors.into_iter().flatten().collect();
        for (i, (p, _)) in errors.iter().enumerate() {
            if errors[..i].iter().any(|(q, _)| q == p) {
                return Err(usage(
                    clap::error::ErrorKind::ValueValidation,
                    format!("--error gives '{p}' twice; give each parameter once"),
                ));
            }
        }
        let source = match (errors.is_empty(), self.k_sigma) {
            (false, None) => MapSource::Errors(errors),
            (true, Some(k)) => MapSource::KSigma(k),
            _ => {
                return Err(usage(
                    clap::error::ErrorKind::ArgumentConflict,
                    "give either --error NAME=VALUE or --k-sigma K, not both",
                ))
            }
        };
        Ok(MapConfig {
            model,
            source,
            distance_mm: self.distance,
            grid: self.grid,
            paper: self.paper,
            out: self.out,
        })
    }
}

fn number(text: &str) -> Option<f64> {
    text.trim().parse::<f64>().ok().filter(|v| v.is_finite())
}

/// A non-negative, finite length in mm.
fn non_negative_mm(text: &str) -> Result<f64, String> {
    match number(text) {
        Some(v) if v >= 0.0 => Ok(v),
        _ => Err(format!("expected a length of 0 mm or more, found '{text}'")),
    }
}

/// A positive, finite number.
fn positive_number(text: &str) -> Result<f64, String> {
    match number(text) {
        Some(v) if v > 0.0 => Ok(v),
        _ => Err(format!("expected a positive number, found '{text}'")),
    }
}

/// An angle in degrees, 0 to 90.
fn angle_deg(text: &str) -> Result<f64, String> {
    match number(text) {
        Some(v) if (0.0..=90.0).contains(&v) => Ok(v),
        _ => Err(format!(
            "expected an angle from 0 to 90 degrees, found '{text}'"
        )),
    }
}

/// A grid size, 2 to MAX_GRID.
fn grid_size(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if (2..=MAX_GRID).contains(&n) => Ok(n),
        _ => Err(format!(
            "expected 2 to {MAX_GRID} points per side, found '{text}'"
        )),
    }
}

/// `--plane NX,NY,NZ,D`.
fn parse_plane(text: &str) -> Result<PlaneSpec, String> {
    let values: Vec<Option<f64>> = text.split(',').map(number).collect();
    let [Some(nx), Some(ny), Some(nz), Some(d)] = values[..] else {
        return Err(format!(
            "expected four numbers NX,NY,NZ,D (the plane n.P = d, sensor frame, d in mm), found \
             '{text}'"
        ));
    };
    let normal = Vector3::new(nx, ny, nz);
    Plane::new(normal, d).map_err(|e| e.to_string())?;
    Ok(PlaneSpec {
        normal,
        offset_mm: d,
    })
}

/// `--error f=0.05,cx=0.02`.
fn parse_error_list(text: &str) -> Result<Vec<(Param, f64)>, String> {
    let mut out = Vec::new();
    for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (name, value) = item
            .split_once('=')
            .ok_or_else(|| format!("expected NAME=VALUE such as f=0.05, found '{item}'"))?;
        let p: Param = name.parse().map_err(|e: UnknownParam| e.to_string())?;
        let v = number(value)
            .ok_or_else(|| format!("expected a finite number for {p}, found '{value}'"))?;
        out.push((p, v));
    }
    if out.is_empty() {
        return Err("expected NAME=VALUE such as f=0.05".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;
    use crate::cli::Job;

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
            Job::Aoa(AoaConfig {
                calibration: "c.json".into(),
                points: "p.csv".into(),
                out: None,
                point_sigma_mm: Some(0.001),
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
        let Job::Map(config) = job else { panic!() };
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
        let Job::Map(config) = job else { panic!() };
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
}
