//! `psdcal simulate-positioning`: a rig of calibrated sensors above
//! emitters at known positions (psdcal-sim's `room`), written as files so
//! that `psdcal locate --rig` and `psdcal evaluate` run end to end.
//!
//! Sensor `k` (1-based id `s<k>`): a calibration data set simulated with
//! seed `1000 seed + k` (wrapping; distinct for every seed and sensor) (the paper's lens and template poses, through the
//! signal chain at the SNR) into `s<k>/`, calibrated from automatic
//! initialisation (f, cx, cy, k1, k2) into `s<k>/calibration.json`. The room
//! (sensor poses, emitters on the floor) and every emitter observation come
//! from ChaCha8 seeded with `seed` on stream 1, through each sensor's true
//! model and signal chain. Written: `rig.json`, `rig_points.csv` (emitter,
//! sensor, x_mm, y_mm) and `truth.csv` (emitter, x_mm, y_mm, z_mm, world
//! frame).

use std::path::PathBuf;

use psdcal_io::write_atomic_bytes;
use psdcal_model::PsdGeometry;
use psdcal_sim::room::{observe_emitter, Room, RoomOptions, RoomSensor};
use psdcal_sim::{Lens, SimulationOptions, TemplateKind};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::base::error::{Error, Result};
use crate::base::options::CalibrationOptions;
use crate::base::table::{num, Table};
use crate::dataset::data_set::{DataSet, DataSetFiles, LoadOptions, PointSource};
use crate::simulation::simulate::{chain_with_record, simulate_files, SimulateRequest};

/// What to simulate.
#[derive(Debug, Clone, PartialEq)]
pub struct PositioningRequest {
    /// The paper's lens of every sensor.
    pub lens: Lens,
    /// Per-channel SNR, dB (no noise when absent), for the calibration data
    /// and the emitters alike.
    pub snr_db: Option<f64>,
    /// Images of each sensor's calibration data.
    pub images: usize,
    /// Record length, cycles.
    pub record_cycles: usize,
    /// The room.
    pub room: RoomOptions,
    /// Seed of every random draw.
    pub seed: u64,
    /// Output folder (created if missing).
    pub out: PathBuf,
    /// Replace files in `out` that psdcal did not write there
    /// (docs/formats.md, "Output folders").
    pub force: bool,
}

/// What was written.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulatedRig {
    /// One line describing the simulation.
    pub description: String,
    /// Sensors (each calibrated).
    pub sensors: usize,
    /// Emitters.
    pub emitters: usize,
    /// RMS of the measured − true impact point over every emitter
    /// observation, per axis, mm: the `--point-sigma` for `locate`.
    pub point_noise_mm: [f64; 2],
    /// Files written, relative to the output folder.
    pub files: Vec<String>,
}

impl SimulatedRig {
    /// The point noise to give `locate --point-sigma`: the RMS over both
    /// axes, mm.
    pub fn point_sigma_mm(&self) -> f64 {
        self.point_noise_mm[0].hypot(self.point_noise_mm[1]) / 2f64.sqrt()
    }

    /// What `simulate-positioning` prints.
    pub fn text(&self, out: &std::path::Path) -> String {
        let [nx, ny] = self.point_noise_mm;
        format!(
            "{}\nwrote {} files into {}; measurement noise {nx:.3e} mm (x), {ny:.3e} mm (y): \
             pass --point-sigma {:.3e} to locate",
            self.description,
            self.files.len(),
            out.display(),
            self.point_sigma_mm()
        )
    }

    /// What `simulate-positioning --json` prints.
    pub fn to_json(&self, out: &std::path::Path) -> serde_json::Value {
        serde_json::json!({
            "out": out.display().to_string(),
            "sensors": self.sensors,
            "emitters": self.emitters,
            "point_noise_mm": self.point_noise_mm,
            "point_sigma_mm": self.point_sigma_mm(),
            "files": self.files,
        })
    }
}

/// Simulates a sensor's calibration data set into `dir` (the paper's
/// `lens`, template poses and signal chain at `snr_db`, seed `seed`) and
/// calibrates it into `dir/calibration.json`.
pub(crate) fn calibrated_sensor_files(
    lens: Lens,
    snr_db: Option<f64>,
    images: usize,
    record_cycles: usize,
    seed: u64,
    dir: &std::path::Path,
) -> Result<()> {
    simulate_files(&SimulateRequest {
        lens,
        snr_db,
        imbalance: false,
        psd_distortion: false,
        psd_nonlinearity: false,
        images,
        template: TemplateKind::Scatter14,
        record_cycles,
        seed,
        out: dir.to_path_buf(),
        // The caller claims the folder's files (`OutputFolder::claim`).
        force: true,
    })?;
    let set = DataSet::from_files(
        &DataSetFiles {
            template: dir.join("template.csv"),
            points: PointSource::Observations(dir.join("observations.csv")),
            gains: None,
        },
        &LoadOptions::default(),
    )?;
    let calibrated =
        crate::calibration::calibrate::calibrate(&set, &CalibrationOptions::default())?;
    calibrated.write(&set, &dir.join("calibration.json"), None)?;
    Ok(())
}

/// The files [`calibrated_sensor_files`] writes.
pub(crate) const SENSOR_FILES: [&str; 5] = [
    "template.csv",
    "observations.csv",
    "signals.csv",
    "truth.json",
    "calibration.json",
];

/// Claims the files of a rig of `sensors` sensors in `out` (each sensor's
/// [`SENSOR_FILES`] in `s<k>/`, and `rig_files`; `force`: any file) and
/// creates the folder.
pub(crate) fn claim_rig_folder(
    out: &std::path::Path,
    sensors: usize,
    rig_files: &[&str],
    force: bool,
) -> Result<psdcal_io::OutputFolder> {
    let names: Vec<String> = (1..=sensors)
        .flat_map(|k| SENSOR_FILES.map(|f| format!("s{k}/{f}")))
        .chain(rig_files.iter().map(|f| f.to_string()))
        .collect();
    let folder = psdcal_io::OutputFolder::claim(out, &names, force)?;
    std::fs::create_dir_all(out).map_err(|e| Error::OutputFolder {
        path: out.to_path_buf(),
        message: format!("cannot create the output folder {}: {e}", out.display()),
    })?;
    Ok(folder)
}

/// The rig's files.
const RIG_FILES: [&str; 3] = ["rig.json", "rig_points.csv", "truth.csv"];

/// Simulates, calibrates and writes the rig (module documentation).
pub fn simulate_positioning(request: &PositioningRequest) -> Result<SimulatedRig> {
    let out = &request.out;
    let truth = request.lens.model();
    let geometry = PsdGeometry::default();
    let mut rng = ChaCha8Rng::seed_from_u64(request.seed);
    rng.set_stream(1);
    let room = Room::draw(&request.room, &truth, &geometry, &mut rng)?;
    let folder = claim_rig_folder(out, room.sensors.len(), &RIG_FILES, request.force)?;
    let mut files = Vec::new();
    let mut sensors_json = Vec::new();
    for (k, pose) in room.sensors.iter().enumerate() {
        let id = format!("s{}", k + 1);
        let dir = out.join(&id);
        calibrated_sensor_files(
            request.lens,
            request.snr_db,
            request.images,
            request.record_cycles,
            request.seed.wrapping_mul(1000).wrapping_add(k as u64 + 1),
            &dir,
        )?;
        for f in SENSOR_FILES {
            files.push(format!("{id}/{f}"));
        }
        sensors_json.push(serde_json::json!({
            "id": id,
            "calibration": format!("{id}/calibration.json"),
            "world_from_sensor": {
                "rvec": pose.rvec.as_slice(),
                "t_mm": pose.t.as_slice(),
            },
        }));
    }
    let rig = serde_json::json!({"format": "psdcal-rig", "version": 1, "sensors": sensors_json});
    let text = serde_json::to_string_pretty(&rig)
        .map_err(|e| Error::Input(format!("cannot encode rig.json: {e}")))?;
    write_atomic_bytes(out.join("rig.json"), (text + "\n").as_bytes())?;
    let chain = chain_with_record(request.record_cycles)?;
    let i0 = SimulationOptions::default().photocurrent_a;
    let mut points = Table {
        header: ["emitter", "sensor", "x_mm", "y_mm"]
            .map(String::from)
            .to_vec(),
        rows: Vec::new(),
    };
    let mut truth_rows = Table {
        header: ["emitter", "x_mm", "y_mm", "z_mm"]
            .map(String::from)
            .to_vec(),
        rows: Vec::new(),
    };
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0usize);
    let sensor = RoomSensor {
        truth: &psdcal_model::Model::standard(&truth),
        geometry: &geometry,
        chain: &chain,
        i0,
        snr_db: request.snr_db,
    };
    for (j, e) in room.emitters.iter().enumerate() {
        let emitter = format!("e{}", j + 1);
        for (k, pose) in room.sensors.iter().enumerate() {
            let o = observe_emitter(&sensor, pose, e, &mut rng)?;
            let d = o.measured - o.true_measured;
            (sx, sy, n) = (sx + d.x * d.x, sy + d.y * d.y, n + 1);
            points.rows.push(vec![
                emitter.clone(),
                format!("s{}", k + 1),
                num(o.measured.x),
                num(o.measured.y),
            ]);
        }
        truth_rows
            .rows
            .push(vec![emitter, num(e.x), num(e.y), num(e.z)]);
    }
    points.write_to(Some(&out.join("rig_points.csv")))?;
    truth_rows.write_to(Some(&out.join("truth.csv")))?;
    files.extend(RIG_FILES.map(String::from));
    folder.finish()?;
    let r = &request.room;
    Ok(SimulatedRig {
        description: format!(
            "Simulated by psdcal {}: {} sensors (lens {}, {}) {} mm above the floor, {} mm \
             apart, each calibrated from {} images; {} emitters on the floor; seed {}.",
            env!("CARGO_PKG_VERSION"),
            r.sensors,
            request.lens.number(),
            request
                .snr_db
                .map_or("no noise".to_string(), |s| format!("{s} dB SNR")),
            r.height_mm,
            r.baseline_mm,
            request.images,
            r.emitters,
            request.seed
        ),
        sensors: room.sensors.len(),
        emitters: room.emitters.len(),
        point_noise_mm: [(sx / n as f64).sqrt(), (sy / n as f64).sqrt()],
        files,
    })
}
