//! `psdcal simulate-positioning --moving S`: a rig recording of moving LEDs
//! with their true paths (psdcal-sim's `moving`: four sensors at the
//! ceiling corners, two LEDs by frequency, one pausing), so that
//! `track --rig` and `serve` can be tried without hardware.
//!
//! Sensor `k` (`s<k>`) is calibrated as `simulate-positioning` does (seed
//! `1000 seed + k`); the recording (20 kHz, every impairment but the
//! switching transient) comes from ChaCha8 seeded with `seed` on stream 2.
//! Written: `s<k>/…`, `rig.json`, `tones.csv`, `raw.tdms` (a group per
//! sensor, channels `vx1`…`vy2`, `wf_increment` 1/fs) and `truth_track.csv`
//! (`t_s,led,x_mm,y_mm,z_mm` every 10 ms, world frame). A window's
//! intersection is the LED's mean place over the window: compare the row of
//! `t_s` with the truth at `t_s + window / 2`.

use std::path::PathBuf;

use psdcal_io::{write_atomic, write_atomic_bytes};
use psdcal_model::PsdGeometry;
use psdcal_sim::moving::{MovingPlan, MovingScene};
use psdcal_sim::{Impairments, Lens, SimError};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::base::error::{Error, Result};
use crate::base::table::{num, Table};
use crate::simulation::simulate_positioning::{
    calibrated_sensor_files, claim_rig_folder, SENSOR_FILES,
};

/// The recording's sample rate, Hz.
pub const MOVING_SAMPLE_RATE_HZ: f64 = 20_000.0;

/// The rig's files.
const RIG_FILES: [&str; 4] = ["rig.json", "tones.csv", "raw.tdms", "truth_track.csv"];

/// What to simulate.
#[derive(Debug, Clone, PartialEq)]
pub struct MovingRequest {
    /// The paper's lens of every sensor.
    pub lens: Lens,
    /// Per-channel SNR of the calibration data, dB (none: no noise).
    pub calibration_snr_db: Option<f64>,
    /// Images of each sensor's calibration data.
    pub images: usize,
    /// Length of the recording, s.
    pub duration_s: f64,
    /// White noise per channel of the recording, V.
    pub noise_v: f64,
    /// Seed of every random draw.
    pub seed: u64,
    /// Output folder (created if missing).
    pub out: PathBuf,
    /// Replace files in `out` that psdcal did not write there
    /// (docs/formats.md, "Output folders").
    pub force: bool,
}

/// The default noise per channel, V: each window's (50 ms) intersection is
/// then 10–20 mm off at 2–5 m.
pub const DEFAULT_MOVING_NOISE_V: f64 = 0.01;

/// What was written.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulatedMoving {
    /// One line describing the simulation.
    pub description: String,
    /// Samples in raw.tdms.
    pub samples: usize,
    /// Files written, relative to the output folder.
    pub files: Vec<String>,
}

impl SimulatedMoving {
    /// What the command prints.
    pub fn text(&self, out: &std::path::Path) -> String {
        format!(
            "{}\nwrote {} files into {}; watch it: psdcal serve --rig {d}/rig.json --tones \
             {d}/tones.csv --raw {d}/raw.tdms --realtime --filter cv",
            self.description,
            self.files.len(),
            out.display(),
            d = out.display()
        )
    }

    /// What the command prints with `--json`.
    pub fn to_json(&self, out: &std::path::Path) -> serde_json::Value {
        serde_json::json!({
            "out": out.display().to_string(),
            "samples": self.samples,
            "sample_rate_hz": MOVING_SAMPLE_RATE_HZ,
            "files": self.files,
        })
    }
}

/// Simulates, calibrates and writes the moving scene (module documentation).
pub fn simulate_moving(request: &MovingRequest) -> Result<SimulatedMoving> {
    let out = &request.out;
    if !(request.duration_s.is_finite() && request.duration_s > 0.0 && request.duration_s <= 3600.0)
    {
        return Err(Error::Options(format!(
            "--moving {} s: expected a length between 0 and 3600 s",
            request.duration_s
        )));
    }
    let scene = MovingScene::ceiling_corners();
    let folder = claim_rig_folder(out, scene.sensors.len(), &RIG_FILES, request.force)?;
    let mut files = Vec::new();
    let mut sensors_json = Vec::new();
    let mut ids = Vec::new();
    for (k, pose) in scene.sensors.iter().enumerate() {
        let id = format!("s{}", k + 1);
        calibrated_sensor_files(
            request.lens,
            request.calibration_snr_db,
            request.images,
            crate::simulation::simulate::DEFAULT_RECORD_CYCLES,
            request.seed.wrapping_mul(1000).wrapping_add(k as u64 + 1),
            &out.join(&id),
        )?;
        files.extend(SENSOR_FILES.iter().map(|f| format!("{id}/{f}")));
        sensors_json.push(serde_json::json!({
            "id": id,
            "calibration": format!("{id}/calibration.json"),
            "world_from_sensor": {"rvec": pose.rvec.as_slice(), "t_mm": pose.t.as_slice()},
        }));
        ids.push(id);
    }
    let rig = serde_json::json!({"format": "psdcal-rig", "version": 1, "sensors": sensors_json});
    let text = serde_json::to_string_pretty(&rig)
        .map_err(|e| Error::Input(format!("cannot encode rig.json: {e}")))?;
    write_atomic_bytes(out.join("rig.json"), (text + "\n").as_bytes())?;
    let mut tones = String::from("led,frequency_hz\n");
    for led in &scene.leds {
        tones += &format!("{},{}\n", led.name, num(led.frequency_hz));
    }
    write_atomic_bytes(out.join("tones.csv"), tones.as_bytes())?;
    let samples = (request.duration_s * MOVING_SAMPLE_RATE_HZ).round() as usize;
    let plan = MovingPlan {
        sample_rate_hz: MOVING_SAMPLE_RATE_HZ,
        samples,
        amplitude_at_1m_v: 2.0,
        noise_v: request.noise_v,
        impairments: Impairments {
            transient_v: 0.0,
            ..Impairments::default()
        },
    };
    let truth = psdcal_model::Model::standard(&request.lens.model());
    let geometry = PsdGeometry::default();
    let mut rng = ChaCha8Rng::seed_from_u64(request.seed);
    rng.set_stream(2);
    let mut failure: Option<SimError> = None;
    let mut tdms = psdcal_io::TdmsFrameWriter::with_groups(MOVING_SAMPLE_RATE_HZ, ids.clone());
    let width = 4 * ids.len();
    write_atomic(out.join("raw.tdms"), |w| {
        let mut pending = Vec::with_capacity(4096 * width);
        let generated = plan.generate(&scene, &truth, &geometry, &mut rng, |rows: &[f64]| {
            pending.extend_from_slice(rows);
            if pending.len() >= 4000 * width {
                tdms.write_rows(w, &pending).map_err(GenError::Io)?;
                pending.clear();
            }
            Ok::<(), GenError>(())
        });
        match generated {
            Ok(()) => tdms.write_rows(w, &pending),
            Err(GenError::Io(e)) => Err(e),
            Err(GenError::Sim(e)) => {
                failure = Some(e);
                Err(std::io::Error::other("simulation failed"))
            }
        }
    })
    .map_err(|e| match failure.take() {
        Some(sim) => Error::from(sim),
        None => Error::Io(e),
    })?;
    let mut truth_rows = Table {
        header: ["t_s", "led", "x_mm", "y_mm", "z_mm"]
            .map(String::from)
            .to_vec(),
        rows: Vec::new(),
    };
    let steps = (request.duration_s * 100.0).round() as usize;
    for n in 0..=steps {
        let t = n as f64 / 100.0;
        for led in &scene.leds {
            let p = led.path.position(t);
            truth_rows
                .rows
                .push(vec![num(t), led.name.clone(), num(p.x), num(p.y), num(p.z)]);
        }
    }
    truth_rows.write_to(Some(&out.join("truth_track.csv")))?;
    files.extend(RIG_FILES.map(String::from));
    folder.finish()?;
    Ok(SimulatedMoving {
        description: format!(
            "Simulated by psdcal {}: 4 sensors (lens {}) at the ceiling corners watching 2 LEDs \
             (a: a circle at 0.85 m/s, b: back and forth at up to 1 m/s with pauses) for {} s \
             at {} Hz, {} V noise per channel, DC, hum, drift, 16-bit ADC and a 40 ppm clock; \
             seed {}.",
            env!("CARGO_PKG_VERSION"),
            request.lens.number(),
            num(request.duration_s),
            num(MOVING_SAMPLE_RATE_HZ),
            num(request.noise_v),
            request.seed
        ),
        samples,
        files,
    })
}

/// Why the generation stopped.
enum GenError {
    Io(std::io::Error),
    Sim(SimError),
}

impl From<SimError> for GenError {
    fn from(e: SimError) -> Self {
        GenError::Sim(e)
    }
}
