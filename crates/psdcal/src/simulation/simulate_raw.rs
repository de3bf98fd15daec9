//! `simulate --raw`: the simulated data set also as the raw recording a
//! card would have made of it (psdcal-sim's `raw` module: the clean
//! amplitudes of every (image, LED) modulated, sampled, with white noise at
//! the SNR and the card's impairments), with schedule.csv and, for frequency
//! multiplexing, tones.csv — the input of `demodulate`.
//!
//! Layout: time multiplexing — one record per (image, LED), LEDs in template
//! order within each image, every LED at `f0` = 1 kHz; frequency
//! multiplexing — one record per image, LED `i` of `L` at
//! `f0 + (i − (L−1)/2) Δ` with `Δ` = [`FDMA_SPACING_HZ`]. Records are
//! `record_cycles / f0` long, back to back from `t = 0`, sampled at
//! [`RAW_SAMPLE_RATE_HZ`]. The raw recording's random numbers come from
//! their own stream (seed `seed ⊕ 0x5241_5752`, "RAWR"), so the other
//! files are those `simulate` writes without `--raw`.

use std::io::Write;

use psdcal_io::{
    npy_header, write_atomic, write_csv_frames, write_npy_frames, write_schedule, write_tones,
    IoError, RawFormat, ScheduleRow, Tone, RAW_CSV_HEADER,
};
use psdcal_model::psd::electrode_currents;
use psdcal_sim::raw::Frame;
use psdcal_sim::{Impairments, RawPlan, RawRecord, SimError};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::base::error::{Error, Result};
use crate::simulation::simulate::{led_id, simulate_and_write, SimulateRequest, SimulatedFiles};

/// Sample rate of simulated recordings, Hz.
pub const RAW_SAMPLE_RATE_HZ: f64 = 20_000.0;

/// Modulation frequency of time-multiplexed LEDs (and the centre of the
/// tones), Hz.
pub const RAW_F0_HZ: f64 = 1000.0;

/// Spacing of the tones of frequency multiplexing, Hz.
pub const FDMA_SPACING_HZ: f64 = 50.0;

/// The raw recording to write besides the data set.
#[derive(Debug, Clone, PartialEq)]
pub struct RawRequest {
    /// raw.csv, raw.npy or raw.tdms.
    pub format: RawFormat,
    /// Every LED of an image on at once, each at its own tone.
    pub fdma: bool,
    /// The card's impairments.
    pub impairments: Impairments,
}

/// Simulates the data set (as [`crate::simulation::simulate::simulate_files`]) and writes the raw
/// recording, schedule.csv and (frequency multiplexing) tones.csv beside it.
/// Returns the data set's summary and the raw file names written.
pub fn simulate_raw_files(
    request: &SimulateRequest,
    raw: &RawRequest,
) -> Result<(SimulatedFiles, Vec<String>)> {
    let raw_name = match raw.format {
        RawFormat::Npy => "raw.npy",
        RawFormat::Tdms => "raw.tdms",
        _ => "raw.csv",
    };
    let more = [raw_name, "schedule.csv", "tones.csv"];
    let more = if raw.fdma { &more[..] } else { &more[..2] };
    let (files, sim, folder) = simulate_and_write(request, more)?;
    let leds = sim.template.leds.len();
    let tone = |i: usize| {
        if raw.fdma {
            RAW_F0_HZ + (i as f64 - 0.5 * (leds as f64 - 1.0)) * FDMA_SPACING_HZ
        } else {
            RAW_F0_HZ
        }
    };
    let duration = request.record_cycles as f64 / RAW_F0_HZ;
    let record_samples = (duration * RAW_SAMPLE_RATE_HZ).round() as usize;
    let mut records = Vec::new();
    let mut schedule = Vec::new();
    for image in &sim.images {
        let clean: Vec<(f64, Frame)> = image
            .points
            .iter()
            .map(|p| {
                let a = electrode_currents(
                    &sim.options.geometry,
                    &p.true_measured,
                    sim.options.photocurrent_a,
                )
                .apply_gains(&sim.gains);
                let k = sim.gain_x1;
                (tone(p.led), [a.vx1 * k, a.vx2 * k, a.vy1 * k, a.vy2 * k])
            })
            .collect();
        let mut push = |leds: Vec<(f64, Frame)>, led: Option<String>| {
            let r = records.len() as f64;
            schedule.push(ScheduleRow {
                image: image.id.clone(),
                led,
                t_start_s: r * record_samples as f64 / RAW_SAMPLE_RATE_HZ,
                t_stop_s: (r + 1.0) * record_samples as f64 / RAW_SAMPLE_RATE_HZ,
                line_no: 0,
            });
            records.push(RawRecord { leds });
        };
        if raw.fdma {
            push(clean, None);
        } else {
            for (p, c) in image.points.iter().zip(clean) {
                push(vec![c], Some(led_id(p.led)));
            }
        }
    }
    let plan = RawPlan {
        sample_rate_hz: RAW_SAMPLE_RATE_HZ,
        record_samples,
        records,
        snr_db: request.snr_db,
        impairments: raw.impairments,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(request.seed ^ 0x5241_5752);
    let out = &request.out;
    let name = raw_name;
    let samples = plan.samples() as u64;
    let mut written: u64 = 0;
    let mut failure: Option<SimError> = None;
    let mut tdms = psdcal_io::TdmsFrameWriter::new(RAW_SAMPLE_RATE_HZ);
    write_atomic(out.join(name), |w| {
        match raw.format {
            RawFormat::Npy => w.write_all(&npy_header(samples))?,
            RawFormat::Tdms => {}
            _ => {
                writeln!(w, "# {}", files.description)?;
                writeln!(
                    w,
                    "# Raw recording at {RAW_SAMPLE_RATE_HZ} Hz (V); see schedule.csv."
                )?;
                writeln!(w, "{RAW_CSV_HEADER}")?;
            }
        }
        let result = plan.generate(
            &mut rng,
            |frames: &[Frame]| -> std::result::Result<(), SinkError> {
                match raw.format {
                    RawFormat::Npy => write_npy_frames(w, frames)?,
                    RawFormat::Tdms => tdms.write(w, frames)?,
                    _ => write_csv_frames(w, written, RAW_SAMPLE_RATE_HZ, frames)?,
                }
                written += frames.len() as u64;
                Ok(())
            },
        );
        match result {
            Ok(()) => Ok(()),
            Err(SinkError::Io(e)) => Err(e),
            Err(SinkError::Sim(e)) => {
                failure = Some(e);
                Err(std::io::Error::other("simulation failed"))
            }
        }
    })
    .map_err(|e: IoError| match failure.take() {
        Some(sim) => Error::Simulation(sim),
        None => Error::Io(e),
    })?;
    let what = &files.description;
    write_schedule(
        out.join("schedule.csv"),
        &format!("{what}\nWhich light is on when in {name} (seconds from the first sample)."),
        &schedule,
    )?;
    let mut names = vec![name.to_string(), "schedule.csv".to_string()];
    if raw.fdma {
        let tones: Vec<Tone> = (0..leds)
            .map(|i| Tone {
                led: led_id(i),
                frequency_hz: tone(i),
                line_no: 0,
            })
            .collect();
        write_tones(
            out.join("tones.csv"),
            &format!("{what}\nEach LED's modulation frequency (Hz)."),
            &tones,
        )?;
        names.push("tones.csv".to_string());
    }
    folder.finish()?;
    Ok((files, names))
}

/// The sink's error: writing, or the plan itself.
enum SinkError {
    Io(std::io::Error),
    Sim(SimError),
}

impl From<std::io::Error> for SinkError {
    fn from(e: std::io::Error) -> Self {
        SinkError::Io(e)
    }
}

impl From<SimError> for SinkError {
    fn from(e: SimError) -> Self {
        SinkError::Sim(e)
    }
}
