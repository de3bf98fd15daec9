//! `psdcal track`: raw samples from standard input (or a recording file) →
//! angles of arrival (one sensor) or positions (a rig) per window and LED
//! on standard output, flushed each window (the work is `psdcal::track`).

use std::path::PathBuf;

use crate::messages::Output;
use clap::Args;

/// Angles of arrival per window and LED from raw samples on standard input (live)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct TrackArgs {
    /// The sensor's calibration.json (angles of arrival)
    #[arg(
        long,
        value_name = "FILE",
        required_unless_present = "rig",
        conflicts_with = "rig"
    )]
    pub calibration: Option<PathBuf>,
    /// A rig.json (positions from every sensor's four channels in one stream)
    #[arg(long, value_name = "FILE")]
    pub rig: Option<PathBuf>,
    /// Sample rate of the stream, Hz (a .tdms file carries its own)
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
    /// The LEDs and their modulation frequencies: led, frequency_hz
    #[arg(long, value_name = "FILE")]
    pub tones: PathBuf,
    /// Window length, s (each window is demodulated on its own)
    #[arg(long, value_name = "S", default_value_t = 0.05)]
    pub window: f64,
    /// Read a recording (raw.csv, raw.npy, raw.tdms) instead of standard input
    #[arg(long, value_name = "FILE")]
    pub raw: Option<PathBuf>,
    /// A .tdms file's channels, four per sensor: group/channel,… (default: vx1, vx2, vy1, vy2)
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub channels: Vec<String>,
    /// A rig's tracking filter: none, or cv (constant-velocity Kalman filter per LED)
    #[arg(long, value_name = "none|cv", default_value = "none")]
    pub filter: String,
    /// The cv filter's white acceleration σ, mm/s² (default 400: walking at up to 1 m/s)
    #[arg(long, value_name = "MM_S2")]
    pub accel_sigma: Option<f64>,
}

/// The request of `track` (and `serve`).
pub fn request(
    args: &TrackArgs,
    limits: psdcal::ReadLimits,
) -> anyhow::Result<psdcal::TrackRequest> {
    let target = match (&args.rig, &args.calibration) {
        (Some(rig), _) => psdcal::TrackTarget::Rig(rig.clone()),
        (None, Some(c)) => psdcal::TrackTarget::Sensor(c.clone()),
        (None, None) => anyhow::bail!("give --calibration FILE or --rig FILE"),
    };
    Ok(psdcal::TrackRequest {
        target,
        rate_hz: args.rate,
        tones: args.tones.clone(),
        window_s: args.window,
        config: psdcal::DemodConfig::default(),
        raw: args.raw.clone(),
        channels: args.channels.clone(),
        limits,
        filter: psdcal::TrackFilter::from_name(&args.filter, args.accel_sigma)
            .map_err(anyhow::Error::msg)?,
    })
}

/// Runs `track` (a summary on standard error unless quiet).
pub fn run(args: &TrackArgs, output: Output, limits: psdcal::ReadLimits) -> anyhow::Result<()> {
    let request = request(args, limits)?;
    let summary = psdcal::track(&request, std::io::stdin().lock(), std::io::stdout().lock())?;
    crate::messages::print_warnings(&summary.warnings());
    if output != Output::Quiet {
        crate::messages::say(&format!("{}\n", summary.text()));
    }
    Ok(())
}
