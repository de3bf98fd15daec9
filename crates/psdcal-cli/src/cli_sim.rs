//! Arguments and validated configurations of `psdcal simulate`, `study` and
//! `demo`. Every option is checked here, before any work starts.

use std::path::PathBuf;

use clap::Args;
use psdcal::option_text::{parse_images, parse_snr, parse_threads, parse_trials};
use psdcal::{parse_record_cycles, StudyRequest};

use crate::choice::choice;

/// Simulate a calibration data set through the whole signal chain
#[derive(Debug, Clone, PartialEq, Args)]
pub struct SimulateArgs {
    /// The paper's lens: 1 (f = 25 mm) or 2 (f = 8 mm)
    #[arg(long, value_name = "1|2", default_value = "2", value_parser = choice::<psdcal::Lens>)]
    pub lens: psdcal::Lens,
    /// Per-channel SNR in dB (no noise when absent)
    #[arg(long, value_name = "DB", value_parser = parse_snr, allow_negative_numbers = true)]
    pub snr: Option<f64>,
    /// Unequal amplifier gains (the paper's component tolerances)
    #[arg(long)]
    pub imbalance: bool,
    /// The PSD's own distortion (l1 = -1.3058e-3)
    #[arg(long)]
    pub psd_distortion: bool,
    /// The PSD's own non-radial non-linearity (about 1 % of the size at the
    /// edges; map it with simulate-scan and psd-map)
    #[arg(long)]
    pub psd_nonlinearity: bool,
    /// Number of images (template poses), at least 3
    #[arg(long, value_name = "N", default_value = "9", value_parser = parse_images)]
    pub images: usize,
    /// Template: scatter14 (14 unaligned LEDs) or grid (5 x 5 with lines)
    #[arg(long, value_name = "NAME", default_value = "scatter14", value_parser = choice::<psdcal::TemplateKind>)]
    pub template: psdcal::TemplateKind,
    /// Length of each LED's record in modulation cycles (the first 25 are
    /// the filter's transient; the rest are demodulated). Longer records
    /// average more samples: residuals fall in proportion (the paper's
    /// residual levels correspond to 545 cycles)
    #[arg(long, value_name = "CYCLES", default_value = "65", value_parser = parse_record_cycles)]
    pub record_cycles: usize,
    /// Seed of every random draw
    #[arg(long, value_name = "S", default_value = "1")]
    pub seed: u64,
    /// Output folder (created if missing)
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Simulate these template poses (poses.csv, e.g. from psdcal plan) instead of drawn ones
    #[arg(long, value_name = "FILE", conflicts_with_all = ["raw", "images"])]
    pub poses: Option<PathBuf>,
    /// Also write the raw recording a card would make (raw.csv, raw.npy or raw.tdms, 20 kHz) and schedule.csv
    #[arg(long, value_name = "csv|npy|tdms", value_parser = choice::<psdcal::RawFormat>)]
    pub raw: Option<psdcal::RawFormat>,
    /// With --raw: every LED of an image on at once, each at its own tone (writes tones.csv)
    #[arg(long, requires = "raw")]
    pub fdma: bool,
    /// With --raw: the card's impairments (docs/model.md §8), comma-separated, or none
    #[arg(long, value_name = "LIST", value_delimiter = ',', requires = "raw",
          default_value = "dc,hum,drift,quantise,clock,transients", value_parser = psdcal::Impairment::parse_item)]
    pub impairments: Vec<Option<psdcal::Impairment>>,
}

/// Run the paper's Monte Carlo evaluation (Tables 1-10, Figure 9) next to the paper's numbers
#[derive(Debug, Clone, PartialEq, Args)]
pub struct StudyArgs {
    /// Tables to run: table1 ... table10, fig9, psdmap (the PSD map's condition), or all
    #[arg(value_name = "TABLE", default_value = "all", value_parser = psdcal::parse_study_id)]
    pub tables: Vec<String>,
    /// Trials per condition
    #[arg(long, value_name = "N", default_value = "200", value_parser = parse_trials)]
    pub trials: usize,
    /// Worker threads (default: every core)
    #[arg(long, value_name = "N", value_parser = parse_threads)]
    pub threads: Option<usize>,
    /// Length of each LED's record in modulation cycles (the first 25 are
    /// the filter's transient; the rest are demodulated). Longer records
    /// average more samples: residuals fall in proportion (the paper's
    /// residual levels correspond to 545 cycles)
    #[arg(long, value_name = "CYCLES", default_value = "65", value_parser = parse_record_cycles)]
    pub record_cycles: usize,
    /// Seed of the study
    #[arg(long, value_name = "S", default_value = "1")]
    pub seed: u64,
    /// Output folder for study.md, study.csv, study.json (created if missing)
    #[arg(long, value_name = "DIR", default_value = "study")]
    pub out: PathBuf,
    /// Also write the tables, Figure 9 maps and histograms as DIR/study.html
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// Simulate, calibrate and compare with the truth in a few seconds (start here)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct DemoArgs {
    /// Seed of the simulation
    #[arg(long, value_name = "S", default_value = "2016")]
    pub seed: u64,
}

impl StudyArgs {
    /// The configuration: `all` expands, duplicates go, the paper's order.
    pub fn into_config(self, force: bool) -> StudyRequest {
        StudyRequest {
            tables: psdcal::expand_tables(&self.tables),
            trials: self.trials,
            threads: self.threads,
            seed: self.seed,
            record_cycles: self.record_cycles,
            out: self.out,
            report: self.report,
            force,
        }
    }
}
