//! `psdcal track`: raw samples from standard input → angles of arrival per
//! window and LED on standard output, flushed each window (the work is
//! `psdcal::track`).

use std::path::PathBuf;

use clap::Args;

/// Arguments of `psdcal track`.
#[derive(Debug, Clone, PartialEq, Args)]
pub struct TrackArgs {
    /// The sensor's calibration.json
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// Sample rate of the stream, Hz
    #[arg(long, value_name = "HZ")]
    pub rate: f64,
    /// The LEDs and their modulation frequencies: led, frequency_hz
    #[arg(long, value_name = "FILE")]
    pub tones: PathBuf,
    /// Window length, s (each window is demodulated on its own)
    #[arg(long, value_name = "S", default_value_t = 0.05)]
    pub window: f64,
}

/// Runs `track` (standard input to standard output; a summary on standard
/// error unless quiet).
pub fn run(args: &TrackArgs, output: crate::cli::Output) -> anyhow::Result<()> {
    let request = psdcal::TrackRequest {
        calibration: args.calibration.clone(),
        rate_hz: args.rate,
        tones: args.tones.clone(),
        window_s: args.window,
        config: psdcal::DemodConfig::default(),
    };
    let summary = psdcal::track(&request, std::io::stdin().lock(), std::io::stdout().lock())?;
    if output != crate::cli::Output::Quiet {
        eprintln!(
            "track: {} samples, {} windows, {} malformed lines",
            summary.samples, summary.windows, summary.malformed
        );
    }
    Ok(())
}
