//! Arguments (clap) and validated configurations of `psdcal aoa`,
//! `psdcal locate` and `psdcal map`. Nothing here reads files.

use std::path::PathBuf;

use clap::{ArgGroup, Args};
use psdcal::option_text::{
    angle_deg, grid_size, non_negative_mm, parse_error_list, parse_plane, positive_mm,
    within_k_sigma,
};
use psdcal::{LocateOptions, MapRequest, Param, Plane, ReadLimits};
pub use psdcal::{LocateTarget, MapModel, MapSource};

use crate::messages::Output;

/// Angles of arrival of measured points (or amplitudes) with their uncertainty
#[derive(Debug, Clone, PartialEq, Args)]
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

/// Emitter positions on a plane, or from a rig of sensors, with their 3-D covariance
#[derive(Debug, Clone, PartialEq, Args)]
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
    pub plane: Option<Plane>,
    /// Rig file: sensors with calibrations and poses in a world frame (docs/positioning.md, 'Rig files')
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

/// Maps of the AoA and position errors over the sensor area (the paper's Figure 9)
#[derive(Debug, Clone, PartialEq, Args)]
#[command(group(ArgGroup::new("model").required(true).args(["calibration", "lens"])))]
#[command(group(ArgGroup::new("source").required(true).args(["errors", "k_sigma"])))]
pub struct MapArgs {
    /// Calibration written by psdcal (its model, sensor size and covariance)
    #[arg(long, short = 'c', value_name = "FILE")]
    pub calibration: Option<PathBuf>,
    /// The paper's simulated lens instead of a calibration: 1 (f = 25 mm) or 2 (f = 8 mm), 9 x 9 mm PSD
    #[arg(long, value_name = "N", value_enum)]
    pub lens: Option<psdcal::Lens>,
    /// Parameter error NAME=VALUE (repeatable or comma-separated), e.g. f=0.05,cx=0.02,k1=1e-4
    #[arg(long = "error", value_name = "NAME=VALUE", value_parser = parse_error_list, allow_hyphen_values = true)]
    pub errors: Vec<Vec<(Param, f64)>>,
    /// Use the calibration's covariance at K standard deviations instead of --error
    #[arg(long, value_name = "K", value_parser = within_k_sigma, allow_negative_numbers = true)]
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

/// Validated configuration of `psdcal locate`.
#[derive(Debug, Clone, PartialEq)]
pub struct LocateConfig {
    pub target: LocateTarget,
    pub points: PathBuf,
    pub out: Option<PathBuf>,
    pub options: LocateOptions,
    pub point_sigma_given: bool,
}

fn usage(kind: clap::error::ErrorKind, message: impl std::fmt::Display) -> clap::Error {
    clap::Error::raw(kind, message)
}

pub(crate) fn json_needs_out(
    command: &str,
    out: &Option<PathBuf>,
    output: Output,
) -> Result<(), clap::Error> {
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

impl LocateArgs {
    /// The validated configuration.
    pub fn into_config(self, output: Output) -> Result<LocateConfig, clap::Error> {
        json_needs_out("locate", &self.out, output)?;
        let conflict = |m: &str| usage(clap::error::ErrorKind::ArgumentConflict, m);
        if self.unweighted && self.rig.is_none() {
            return Err(conflict("--unweighted applies to --rig only"));
        }
        let target =
            match (self.distance, self.plane, self.rig, self.calibration) {
                (Some(s), None, None, Some(calibration)) => LocateTarget::Plane {
                    calibration,
                    plane: Plane::parallel(s).map_err(|e| conflict(&e.to_string()))?,
                },
                (None, Some(plane), None, Some(calibration)) => {
                    LocateTarget::Plane { calibration, plane }
                }
                (None, None, Some(rig), None) => LocateTarget::Rig(rig),
                _ => return Err(conflict(
                    "give exactly one of --distance, --plane (both with --calibration) and --rig",
                )),
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
    /// The map's request (its calibration read within `limits`) and where
    /// its table goes.
    pub fn into_config(
        self,
        output: Output,
        limits: ReadLimits,
    ) -> Result<(MapRequest, Option<PathBuf>), clap::Error> {
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
            (None, Some(lens)) => {
                MapModel::PaperLens(if lens == psdcal::Lens::One { 1 } else { 2 })
            }
            _ => {
                return Err(usage(
                    clap::error::ErrorKind::ArgumentConflict,
                    "give exactly one of --calibration and --lens",
                ))
            }
        };
        let errors = self.errors.into_iter().flatten().collect();
        let source = MapSource::choose(errors, self.k_sigma).map_err(|e| match e {
            psdcal::MapSourceError::Repeated(_) => {
                usage(clap::error::ErrorKind::ValueValidation, e)
            }
            _ => usage(clap::error::ErrorKind::ArgumentConflict, e),
        })?;
        let request = MapRequest {
            model,
            source,
            distance_mm: self.distance,
            grid: self.grid,
            paper: self.paper,
            limits,
        };
        Ok((request, self.out))
    }
}
