//! One simulated data set written as psdcal's input files plus truth.json
//! (template.csv, observations.csv, signals.csv, truth.json).

use std::path::{Path, PathBuf};

use psdcal_io::{
    write_observations, write_signals, write_template, write_truth, IntrinsicsRecord,
    ObservationRow, OutputFolder, SensorSize, SignalRowOut, SimulationSettings, TemplateLed,
    TrueGains, TruePose, Truth, TRUTH_FORMAT, TRUTH_VERSION,
};
use psdcal_model::Pose;
use psdcal_sim::{
    simulate, simulate_at, ChainConfig, Lens, SignalChain, Simulation, SimulationOptions,
    TemplateKind,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::base::error::{Error, Result};
use crate::base::summary::Summary;

/// Default record length of the signal chain, cycles.
pub const DEFAULT_RECORD_CYCLES: usize = 65;

/// Longest record accepted, cycles (10 s per LED at 1 kHz).
pub const MAX_RECORD_CYCLES: usize = 10_000;

/// Cycles at the start of a record that the filter's transient spoils
/// (a record must be longer).
pub fn transient_cycles() -> usize {
    ChainConfig::default().transient_cycles
}

/// `--record-cycles N`: a record longer than the filter transient, at most
/// [`MAX_RECORD_CYCLES`] cycles.
pub fn parse_record_cycles(text: &str) -> Result<usize, String> {
    let transient = transient_cycles();
    match text.trim().parse::<usize>() {
        Ok(n) if n > transient && n <= MAX_RECORD_CYCLES => Ok(n),
        _ => Err(format!(
            "expected a record length from {} to {} cycles (more than the \
             {transient}-cycle filter transient), found '{text}'",
            transient + 1,
            MAX_RECORD_CYCLES
        )),
    }
}

/// The default signal chain with records of `record_cycles` cycles.
pub fn chain_with_record(record_cycles: usize) -> Result<SignalChain> {
    let config = ChainConfig {
        record_cycles,
        ..ChainConfig::default()
    };
    SignalChain::new(config)
        .map_err(|e| Error::Options(format!("record length {record_cycles} cycles: {e}")))
}

/// ` --record-cycles N` when `n` is not the default, for reproduce lines.
pub fn record_cycles_flag(n: usize) -> String {
    if n == DEFAULT_RECORD_CYCLES {
        String::new()
    } else {
        format!(" --record-cycles {n}")
    }
}

/// What to simulate.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulateRequest {
    /// The paper's lens.
    pub lens: Lens,
    /// Per-channel SNR, dB (no noise when absent).
    pub snr_db: Option<f64>,
    /// Unequal amplifier gains.
    pub imbalance: bool,
    /// The PSD's own distortion.
    pub psd_distortion: bool,
    /// The PSD's non-radial non-linearity (docs/model.md §8.3).
    pub psd_nonlinearity: bool,
    /// Images (template poses).
    pub images: usize,
    /// The template.
    pub template: TemplateKind,
    /// Record length, cycles.
    pub record_cycles: usize,
    /// Seed of every random draw.
    pub seed: u64,
    /// Output folder (created if missing).
    pub out: PathBuf,
    /// Replace files in `out` that psdcal did not write there (otherwise
    /// refused before anything is written; docs/formats.md, "Output
    /// folders").
    pub force: bool,
}

/// What was written.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulatedFiles {
    /// One line describing the simulation.
    pub description: String,
    /// Images written.
    pub images: usize,
    /// Points written.
    pub points: usize,
}

impl SimulatedFiles {
    /// The summary of a data set written into the folder `out` (with the
    /// files `more` besides the four every simulation writes).
    pub fn summary(&self, out: &std::path::Path, more: &[String]) -> Summary {
        let mut names = vec![
            "template.csv".to_string(),
            "observations.csv".to_string(),
            "signals.csv".to_string(),
            "truth.json".to_string(),
        ];
        names.extend(more.iter().cloned());
        let json = serde_json::json!({
            "out": out.display().to_string(),
            "images": self.images,
            "points": self.points,
            "files": names,
        });
        let shown: Vec<String> = names
            .iter()
            .map(|n| out.join(n).display().to_string())
            .collect();
        let text = format!(
            "{}\nwrote {} ({} images, {} points)",
            self.description,
            shown.join(", "),
            self.images,
            self.points
        );
        Summary::new(text, json)
    }
}

/// Simulates and writes the data set.
pub fn simulate_files(request: &SimulateRequest) -> Result<SimulatedFiles> {
    let (files, _, folder) = simulate_and_write(request, &[])?;
    folder.finish()?;
    Ok(files)
}

/// A simulated data set in memory: the rows of template.csv,
/// observations.csv and signals.csv, and truth.json's record.
#[derive(Debug, Clone)]
pub struct SimulatedData {
    /// One line describing the simulation.
    pub description: String,
    /// The template's LEDs (named `1 … N`).
    pub template: Vec<TemplateLed>,
    /// The measured impact points.
    pub observations: Vec<ObservationRow>,
    /// The demodulated electrode amplitudes of the same points.
    pub signals: Vec<SignalRowOut>,
    /// The truth: model, gains, poses, settings.
    pub truth: Truth,
}

/// Simulates the data set of `request` in memory (`request.out` is not
/// used): what [`simulate_files`] writes.
pub fn simulate_data(request: &SimulateRequest) -> Result<SimulatedData> {
    simulate_in_memory(request, None).map(|(data, _)| data)
}

fn simulate_in_memory(
    request: &SimulateRequest,
    poses: Option<&[Pose]>,
) -> Result<(SimulatedData, Simulation)> {
    let options = SimulationOptions {
        lens: request.lens,
        snr_db: request.snr_db,
        imbalance: request.imbalance,
        psd_distortion: request.psd_distortion,
        psd_nonlinearity: request.psd_nonlinearity,
        images: request.images,
        template: request.template,
        chain: chain_with_record(request.record_cycles)?,
        ..SimulationOptions::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(request.seed);
    let sim = match poses {
        Some(poses) => simulate_at(&options, poses, &mut rng)?,
        None => simulate(&options, &mut rng)?,
    };
    let observations: Vec<ObservationRow> = sim
        .images
        .iter()
        .flat_map(|im| {
            im.points.iter().map(|p| ObservationRow {
                image: im.id.clone(),
                led: led_id(p.led),
                x_mm: p.measured.x,
                y_mm: p.measured.y,
            })
        })
        .collect();
    let signals: Vec<SignalRowOut> = sim
        .images
        .iter()
        .flat_map(|im| {
            im.points.iter().map(|p| SignalRowOut {
                image: im.id.clone(),
                led: led_id(p.led),
                amplitudes: p.amplitudes,
            })
        })
        .collect();
    let data = SimulatedData {
        description: describe(request),
        template: template_leds(&sim),
        observations,
        signals,
        truth: truth(&sim, request),
    };
    Ok((data, sim))
}

/// [`simulate_files`], also returning the simulation (for the raw
/// recording of the same data set).
/// `more` names the files the caller writes into the folder after the data
/// set; the caller records them all ([`OutputFolder::finish`]).
pub(crate) fn simulate_and_write(
    request: &SimulateRequest,
    more: &[&str],
) -> Result<(SimulatedFiles, Simulation, OutputFolder)> {
    simulate_and_write_at(request, None, more)
}

/// Simulates the data set at the poses of a poses.csv (`psdcal simulate
/// --poses`, docs/formats.md) instead of drawn ones, and writes it;
/// `request.images` is replaced by the number of poses; poses.csv is read
/// within `limits`.
pub fn simulate_files_at_poses(
    request: &SimulateRequest,
    poses: &Path,
    limits: psdcal_io::ReadLimits,
) -> Result<SimulatedFiles> {
    let file = psdcal_io::Poses::read_with(poses, limits)?;
    let poses: Vec<Pose> = file
        .rows
        .iter()
        .map(|r| Pose::new(r.rvec.into(), r.t_mm.into()))
        .collect();
    let request = SimulateRequest {
        images: poses.len(),
        ..request.clone()
    };
    let (files, _, folder) = simulate_and_write_at(&request, Some(&poses), &[])?;
    folder.finish()?;
    Ok(files)
}

/// The files every simulation writes into its folder.
const DATA_SET_FILES: [&str; 4] = [
    "template.csv",
    "observations.csv",
    "signals.csv",
    "truth.json",
];

fn simulate_and_write_at(
    request: &SimulateRequest,
    poses: Option<&[Pose]>,
    more: &[&str],
) -> Result<(SimulatedFiles, Simulation, OutputFolder)> {
    let out = &request.out;
    let names: Vec<String> = DATA_SET_FILES
        .iter()
        .chain(more)
        .map(|n| n.to_string())
        .collect();
    std::fs::create_dir_all(out).map_err(|e| Error::OutputFolder {
        path: out.clone(),
        message: format!("cannot create the output folder {}: {e}", out.display()),
    })?;
    let folder = OutputFolder::claim(out, &names, request.force)?;
    let (data, sim) = simulate_in_memory(request, poses)?;
    let what = &data.description;
    write_template(
        out.join("template.csv"),
        &format!("{what}\nTemplate {} (mm).", request.template.name()),
        &data.template,
    )?;
    write_observations(
        out.join("observations.csv"),
        &format!("{what}\nImpact points from the demodulated amplitudes (balanced formula)."),
        &data.observations,
    )?;
    write_signals(
        out.join("signals.csv"),
        &format!("{what}\nDemodulated electrode amplitudes (V)."),
        &data.signals,
    )?;
    write_truth(out.join("truth.json"), &data.truth)?;
    let files = SimulatedFiles {
        description: data.description.clone(),
        images: sim.images.len(),
        points: data.observations.len(),
    };
    Ok((files, sim, folder))
}

pub(crate) fn led_id(index: usize) -> String {
    format!("{}", index + 1)
}

fn describe(r: &SimulateRequest) -> String {
    format!(
        "Simulated by psdcal {}: lens {}, {}{}{}, {} images, seed {}.",
        env!("CARGO_PKG_VERSION"),
        r.lens.number(),
        r.snr_db
            .map_or("no noise".to_string(), |s| format!("{s} dB SNR")),
        if r.imbalance { ", gain imbalance" } else { "" },
        if r.psd_distortion {
            ", PSD distortion"
        } else {
            ""
        }
        .to_string()
            + if r.psd_nonlinearity {
                ", PSD non-linearity"
            } else {
                ""
            },
        r.images,
        r.seed
    ) + &if r.record_cycles == DEFAULT_RECORD_CYCLES {
        String::new()
    } else {
        format!(" Records of {} cycles.", r.record_cycles)
    }
}

fn template_leds(sim: &Simulation) -> Vec<TemplateLed> {
    sim.template
        .leds
        .iter()
        .enumerate()
        .map(|(i, p)| TemplateLed {
            id: led_id(i),
            x_mm: p.x,
            y_mm: p.y,
            lines: sim
                .template
                .lines
                .iter()
                .zip(&sim.template.line_names)
                .filter(|(leds, _)| leds.contains(&i))
                .map(|(_, name)| name.clone())
                .collect(),
        })
        .collect()
}

fn truth(sim: &Simulation, r: &SimulateRequest) -> Truth {
    let chain = sim.options.chain.config();
    let m = &sim.truth;
    Truth {
        format: TRUTH_FORMAT.into(),
        version: TRUTH_VERSION,
        simulation: SimulationSettings {
            seed: r.seed,
            lens: r.lens.number(),
            snr_db: r.snr_db,
            imbalance: r.imbalance,
            psd_distortion: r.psd_distortion,
            psd_nonlinearity: r.psd_nonlinearity,
            template: r.template.name().into(),
            images: r.images,
            photocurrent_a: sim.options.photocurrent_a,
            f0_hz: chain.f0_hz,
            sample_rate_hz: chain.sample_rate_hz,
            bandwidth_hz: chain.bandwidth_hz,
            filter_order: chain.filter_order,
            record_s: chain.record_cycles as f64 / chain.f0_hz,
            demodulation: format!("{:?}", chain.demodulation),
        },
        sensor: SensorSize {
            lx_mm: sim.options.geometry.lx,
            ly_mm: sim.options.geometry.ly,
        },
        intrinsics: IntrinsicsRecord {
            f_mm: m.intrinsics.f,
            cx_mm: m.intrinsics.cx,
            cy_mm: m.intrinsics.cy,
            skew: m.intrinsics.skew,
        },
        distortion: m.distortion,
        gains: TrueGains {
            x1_v_per_a: sim.gain_x1,
            x2: sim.gains.x2,
            y1: sim.gains.y1,
            y2: sim.gains.y2,
        },
        images: sim
            .images
            .iter()
            .zip(&sim.poses)
            .map(|(im, p)| TruePose {
                id: im.id.clone(),
                rvec: [p.rvec.x, p.rvec.y, p.rvec.z],
                t_mm: [p.t.x, p.t.y, p.t.z],
            })
            .collect(),
    }
}
