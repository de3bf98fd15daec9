//! `psdcal simulate-positioning`: a calibrated rig and emitters at known
//! positions written as files (the library's `simulate_positioning`).

use std::path::PathBuf;

use clap::Args;
use psdcal::{PositioningRequest, RoomOptions};

use crate::choice::choice;
use crate::messages::Output;
use psdcal::option_text::positive_mm;
use psdcal::option_text::{parse_images, parse_snr};

/// Simulate a calibrated rig of sensors and emitters at known positions (rig.json, rig_points.csv, truth.csv)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct PositioningArgs {
    /// The paper's lens of every sensor: 1 (f = 25 mm) or 2 (f = 8 mm)
    #[arg(long, value_name = "1|2", default_value = "2", value_parser = choice::<psdcal::Lens>)]
    pub lens: psdcal::Lens,
    /// Per-channel SNR in dB, calibration data and emitters (no noise when absent)
    #[arg(long, value_name = "DB", value_parser = parse_snr, allow_negative_numbers = true)]
    pub snr: Option<f64>,
    /// Sensors on the ceiling (a circle of diameter --baseline), at least 2
    #[arg(long, value_name = "N", default_value = "2", value_parser = clap::value_parser!(u16).range(2..=64))]
    pub sensors: u16,
    /// Height of the sensors above the floor, mm
    #[arg(long, value_name = "MM", default_value = "2500", value_parser = positive_mm)]
    pub height: f64,
    /// Distance between the sensors (the circle's diameter), mm
    #[arg(long, value_name = "MM", default_value = "1000", value_parser = positive_mm)]
    pub baseline: f64,
    /// Emitters on the floor, seen by every sensor
    #[arg(long, value_name = "N", default_value = "100", value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub emitters: u32,
    /// Images of each sensor's calibration data, at least 3
    #[arg(long, value_name = "N", default_value = "9", value_parser = parse_images)]
    pub images: usize,
    /// Seed of every random draw
    #[arg(long, value_name = "S", default_value = "1")]
    pub seed: u64,
    /// Output folder (created if missing)
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Instead: a recording of 2 LEDs moving for S seconds under 4 ceiling sensors (raw.tdms, truth_track.csv)
    #[arg(long, value_name = "S")]
    pub moving: Option<f64>,
}

/// Runs `simulate-positioning`.
pub fn run(a: &PositioningArgs, output: Output, force: bool) -> anyhow::Result<()> {
    if let Some(duration_s) = a.moving {
        let moving = psdcal::simulate_moving(&psdcal::MovingRequest {
            lens: a.lens,
            calibration_snr_db: a.snr,
            images: a.images,
            duration_s,
            noise_v: psdcal::DEFAULT_MOVING_NOISE_V,
            seed: a.seed,
            out: a.out.clone(),
            force,
        })?;
        let summary = psdcal::Summary::new(moving.text(&a.out), moving.to_json(&a.out));
        return crate::messages::emit(output, &summary);
    }
    let rig = psdcal::simulate_positioning(&PositioningRequest {
        lens: a.lens,
        snr_db: a.snr,
        images: a.images,
        record_cycles: psdcal::DEFAULT_RECORD_CYCLES,
        room: RoomOptions {
            sensors: a.sensors.into(),
            height_mm: a.height,
            baseline_mm: a.baseline,
            emitters: a.emitters as usize,
            ..RoomOptions::default()
        },
        seed: a.seed,
        out: a.out.clone(),
        force,
    })?;
    let summary = psdcal::Summary::new(rig.text(&a.out), rig.to_json(&a.out));
    crate::messages::emit(output, &summary)
}
