//! The arguments shared by several commands (the data set's, `calibrate`'s,
//! `correct`'s) and the validated configuration of `calibrate`.

use std::path::PathBuf;

use clap::{ArgGroup, Args};
use psdcal::option_text::{parse_assignment, parse_fit, parse_robust, parse_uncertainty};
use psdcal::option_text::{positive_mm, side_mm, FitList};
use psdcal::{CalibrationOptions, DataSetFiles, LoadOptions, Param, PsdGeometry, ReadLimits};
use psdcal::{CostKind, NoiseModel, PointSource, Preliminary, RobustLoss, Uncertainty};

// Also the data-set arguments of `calibrate` and `calibrate-in-situ`.
/// Validate a calibration data set and summarise images, points and sensor coverage
#[derive(Debug, Clone, PartialEq, Args)]
#[command(group(ArgGroup::new("input").required(true).args(["observations", "signals"])))]
pub struct DataSetArgs {
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
    /// Treat every data warning as an error instead of dropping the data
    #[arg(long)]
    pub strict: bool,
}

/// Calibrate a sensor from images of an LED template (adapted Zhang method + Levenberg-Marquardt)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct CalibrateArgs {
    #[command(flatten)]
    pub data: DataSetArgs,
    /// Where to write calibration.json (atomically)
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Parameters to estimate, exactly these, comma-separated (the others
    /// stay fixed); `a` frees the y axis's own scale (fy = f (1 + a)); add
    /// `gains` to self-calibrate the amplifier gains (needs --signals).
    /// Without it the data choose: f,cx,cy,k1,k2 and whichever of a; k3;
    /// p1,p2; l1; skew lower the held-out angle error beyond its noise
    #[arg(long, value_name = "LIST", value_parser = parse_fit)]
    pub fit: Option<FitList>,
    /// Nominal focal length of the lens, mm (narrows the start's search)
    #[arg(long, value_name = "MM", value_parser = positive_mm)]
    pub focal_guess: Option<f64>,
    /// Cost to minimise: template (the paper's template-plane error) or image
    #[arg(long, value_name = "KIND", value_enum, default_value_t = CostKind::Template)]
    pub cost: CostKind,
    /// Noise weighting of the cost: uniform (unweighted, the paper's),
    /// channel-snr (the same SNR on every electrode channel, each record's own
    /// from signals.csv's snr_db when given: points near the electrodes weigh
    /// more) or channel-floor (the same absolute noise on
    /// every channel: brighter spots weigh more)
    #[arg(long, value_name = "MODEL", value_enum, default_value_t = NoiseModel::Uniform)]
    pub noise: NoiseModel,
    /// Preliminary distortion correction before the linear stage: auto (line
    /// straightness when the template declares lines, else homography
    /// consistency), straightness, homography, or off
    #[arg(long, value_name = "METHOD", value_enum, default_value_t = Preliminary::Auto)]
    pub preliminary: Preliminary,
    /// Skip the preliminary distortion correction (same as --preliminary off)
    #[arg(long, conflicts_with = "preliminary")]
    pub no_preliminary: bool,
    /// Skip the data normalisation of the homographies
    #[arg(long)]
    pub no_normalize: bool,
    /// Robust loss: huber:K or cauchy:K, K in units of the residuals' noise σ (estimated)
    #[arg(long, value_name = "LOSS:SCALE", value_parser = parse_robust)]
    pub robust: Option<RobustLoss>,
    /// Covariance of the estimate: jackknife (the default: the analytic σ
    /// raised to the jackknife over images where larger), linear (analytic)
    /// or bootstrap:N[:SEED] (N ≥ 10 refits of images resampled with
    /// replacement; seed 1 by default)
    #[arg(long, value_name = "METHOD", default_value = "jackknife", value_parser = parse_uncertainty)]
    pub uncertainty: Uncertainty,
    /// The PSD's non-linearity map from `psdcal psd-map`, first in the
    /// model and held fixed (its uncertainty carried)
    #[arg(long, value_name = "FILE")]
    pub psd_map: Option<PathBuf>,
    /// Refine the PSD map's coefficients too, its scan's covariance as their prior
    #[arg(long, requires = "psd_map")]
    pub refine_psd_map: bool,
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
}

/// Correct measured points (or electrode amplitudes) to ideal points with a calibration
#[derive(Debug, Clone, PartialEq, Args)]
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

/// Validated configuration of `psdcal calibrate`.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrateConfig {
    pub files: DataSetFiles,
    pub load: LoadOptions,
    pub out: PathBuf,
    pub residuals: Option<PathBuf>,
    pub options: CalibrationOptions,
}

impl DataSetArgs {
    /// The files (with `gains`) and load options; the points come from
    /// exactly one of `--observations` and `--signals` (clap's group makes
    /// one required; this refuses both). The files are read within `limits`.
    pub(crate) fn into_files(
        self,
        gains: Option<PathBuf>,
        limits: ReadLimits,
    ) -> Result<(DataSetFiles, LoadOptions), clap::Error> {
        let points = match (self.observations, self.signals) {
            (Some(path), None) => PointSource::Observations(path),
            (None, Some(path)) => PointSource::Signals(path),
            _ => {
                return Err(clap::Error::raw(
                    clap::error::ErrorKind::ArgumentConflict,
                    "give exactly one of --observations and --signals",
                ))
            }
        };
        let files = DataSetFiles {
            template: self.template,
            points,
            gains,
        };
        let geometry = PsdGeometry {
            lx: self.lx,
            ly: self.ly,
        };
        let load = LoadOptions {
            geometry,
            strict: self.strict,
            limits,
        };
        Ok((files, load))
    }
}
