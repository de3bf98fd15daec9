//! `psdcal demodulate`: a raw recording and its schedule → signals.csv
//! with `snr_db` (the work is `psdcal::demodulate`).

use std::path::PathBuf;

use clap::Args;

use crate::messages::Output;
use psdcal::ReadLimits;

/// Demodulate a raw recording (raw.csv, raw.npy) into signals.csv with a per-record SNR
#[derive(Debug, Clone, PartialEq, Args)]
pub struct DemodulateArgs {
    /// The raw recording: raw.csv (vx1, vx2, vy1, vy2, optional t_s), raw.npy (N×4) or raw.tdms
    #[arg(long, value_name = "FILE")]
    pub raw: PathBuf,
    /// Sample rate, Hz (needed for raw.npy and for raw.csv without t_s; raw.tdms has wf_increment)
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
    /// Which light is on when: image, t_start_s, t_stop_s and optionally led
    #[arg(long, value_name = "FILE")]
    pub schedule: PathBuf,
    /// Each LED's modulation frequency: led, frequency_hz (needed without an led column)
    #[arg(long, value_name = "FILE")]
    pub tones: Option<PathBuf>,
    /// Modulation frequency of LEDs without a tone, Hz
    #[arg(long, value_name = "HZ", default_value_t = 1000.0)]
    pub frequency: f64,
    /// The ADC's full scale, V (samples within one 16-bit step of it are saturated)
    #[arg(long, value_name = "V", default_value_t = 10.0)]
    pub full_scale: f64,
    /// A .tdms file's four channels in the order vx1, vx2, vy1, vy2: group/channel,…
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub channels: Vec<String>,
    /// Where to write signals.csv (atomically)
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// Runs `demodulate`.
pub fn run(args: &DemodulateArgs, output: Output, limits: ReadLimits) -> anyhow::Result<()> {
    let request = psdcal::DemodulateRequest {
        raw: args.raw.clone(),
        rate_hz: args.rate,
        schedule: args.schedule.clone(),
        tones: args.tones.clone(),
        frequency_hz: args.frequency,
        out: args.out.clone(),
        config: psdcal::DemodConfig {
            full_scale_v: args.full_scale,
            ..psdcal::DemodConfig::default()
        },
        channels: args.channels.clone(),
        limits,
    };
    let done = psdcal::demodulate(&request)?;
    let summary = psdcal::Summary::new(done.summary(&args.out), done.to_json());
    crate::messages::emit(output, &summary.warn(&done.warnings))
}
