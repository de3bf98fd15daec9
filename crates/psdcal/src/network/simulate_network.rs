//! `psdcal simulate-network`: a room of sensors, a wand waved through it, a
//! static frame on the floor and test emitters (psdcal-sim's
//! `network_room`), written as the files of `calibrate-network` and
//! `locate --rig`:
//!
//! - `sensors.csv` and each sensor's lab calibration `lab/<id>.json` (the
//!   truth plus a draw from its lab covariance, which it carries);
//! - `wand.csv`, `frame.csv`, `network_points.csv` (frame, sensor, led,
//!   x_mm, y_mm; the static frame's LEDs `L1…`, the wand's `w1…`);
//! - the test emitters: `rig_points.csv` (emitter, sensor, x_mm, y_mm) and
//!   `truth.csv`; the true rig `true_rig.json` with the true lenses
//!   `true/<id>.json` (for the positions obtained with the true poses);
//! - `network_truth.json`: the true poses, the corrupted frames, the point
//!   noise.
//!
//! Everything is drawn from ChaCha8 seeded with `seed` (stream 3), so a
//! seed gives the same files.

use std::path::PathBuf;

use psdcal_io::{write_atomic_bytes, write_calibration, Calibration, OutputFolder, StdDevs};
use psdcal_model::Pose;
use psdcal_sim::network_room::{NetworkRoom, NetworkRoomOptions, NetworkRoomSensor, RoomLed};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::json;

use crate::base::error::{Error, Result};
use crate::base::summary::Summary;
use crate::base::table::{num, Table};
use crate::simulation::simulate::chain_with_record;

/// Simulate a room of sensors, a waved wand, a static frame and test emitters
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct NetworkSimRequest {
    /// Output folder (created if missing)
    #[cfg_attr(feature = "clap", arg(long, value_name = "DIR"))]
    pub out: PathBuf,
    /// Seed of every random draw
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1))]
    pub seed: u64,
    /// Number of sensors
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 8))]
    pub sensors: usize,
    /// Waving time, s
    #[cfg_attr(feature = "clap", arg(long, value_name = "S", default_value_t = 60.0))]
    pub seconds: f64,
    /// Frame rate, Hz
    #[cfg_attr(feature = "clap", arg(long, value_name = "HZ", default_value_t = 50.0))]
    pub rate: f64,
    /// Per-channel SNR, dB
    #[cfg_attr(feature = "clap", arg(long, value_name = "DB", default_value_t = 40.0))]
    pub snr: f64,
    /// Fraction of frames with one wrong sighting
    #[cfg_attr(feature = "clap", arg(long, value_name = "F", default_value_t = 0.03))]
    pub bad_fraction: f64,
    /// A wand of three LEDs on one line (default: a T)
    #[cfg_attr(feature = "clap", arg(long))]
    pub collinear_wand: bool,
    /// Replace files in `out` that psdcal did not write there (otherwise
    /// refused before anything is written; docs/formats.md, "Output
    /// folders"). The command line's global `--force`.
    #[cfg_attr(feature = "clap", arg(skip))]
    pub force: bool,
}

/// The lab record of a simulated sensor (`lab`: its lab values and
/// covariance; otherwise the truth with none).
fn record(s: &NetworkRoomSensor, room: &NetworkRoom, lab: bool) -> Calibration {
    let model = if lab { s.lab } else { s.truth };
    let mut r = Calibration::from_model(&model, &room.geometry);
    if lab {
        r.set_estimated(&s.lab_params);
        let names: Vec<String> = s.lab_params.iter().map(|p| p.name().to_string()).collect();
        let n = names.len();
        r.std = StdDevs(
            names
                .iter()
                .enumerate()
                .map(|(i, name)| (name.clone(), s.lab_covariance[(i, i)].sqrt()))
                .collect(),
        );
        r.covariance = psdcal_io::Covariance {
            parameters: names,
            matrix: (0..n)
                .map(|i| (0..n).map(|j| s.lab_covariance[(i, j)]).collect())
                .collect(),
        };
    }
    r.store_valid_region();
    r
}

fn led_table(names: &[String], points: &[nalgebra::Vector3<f64>]) -> Table {
    Table {
        header: ["led", "X_mm", "Y_mm", "Z_mm"].map(String::from).to_vec(),
        rows: names
            .iter()
            .zip(points)
            .map(|(n, p)| vec![n.clone(), num(p.x), num(p.y), num(p.z)])
            .collect(),
    }
}

fn pose_json(p: &Pose) -> serde_json::Value {
    json!({ "rvec": p.rvec.as_slice(), "t_mm": p.t.as_slice() })
}

/// The files written under fixed names (besides `lab/<id>.json` and
/// `true/<id>.json`).
const FILES: [&str; 8] = [
    "sensors.csv",
    "wand.csv",
    "frame.csv",
    "network_points.csv",
    "rig_points.csv",
    "truth.csv",
    "true_rig.json",
    "network_truth.json",
];

/// Simulates and writes the room (module documentation); refused before
/// anything is written when one of its files in `out` is not psdcal's
/// (unless `request.force`).
pub fn simulate_network(request: &NetworkSimRequest) -> Result<Summary> {
    let out = &request.out;
    let options = NetworkRoomOptions {
        sensors: request.sensors,
        duration_s: request.seconds,
        rate_hz: request.rate,
        snr_db: Some(request.snr),
        bad_fraction: request.bad_fraction,
        collinear_wand: request.collinear_wand,
        ..NetworkRoomOptions::default()
    };
    let chain = chain_with_record(psdcal_sim::ChainConfig::default().record_cycles)?;
    let mut rng = ChaCha8Rng::seed_from_u64(request.seed);
    rng.set_stream(3);
    let room = NetworkRoom::simulate(&options, &chain, &mut rng)?;
    let ids: Vec<String> = (1..=room.sensors.len()).map(|k| format!("s{k}")).collect();
    let names: Vec<String> = FILES
        .iter()
        .map(|f| f.to_string())
        .chain(
            ids.iter()
                .flat_map(|id| [format!("lab/{id}.json"), format!("true/{id}.json")]),
        )
        .collect();
    let folder = OutputFolder::claim(out, &names, request.force)?;
    for d in [out.clone(), out.join("lab"), out.join("true")] {
        std::fs::create_dir_all(&d).map_err(|e| Error::OutputFolder {
            path: d.clone(),
            message: format!("cannot create the output folder {}: {e}", d.display()),
        })?;
    }
    let wand_names: Vec<String> = (1..=room.wand.len()).map(|k| format!("w{k}")).collect();
    let frame_names: Vec<String> = (1..=room.frame_leds.len())
        .map(|k| format!("L{k}"))
        .collect();
    let mut sensors = Table {
        header: vec!["sensor".into(), "calibration".into()],
        rows: vec![],
    };
    let mut true_rig = Vec::new();
    for (k, s) in room.sensors.iter().enumerate() {
        write_calibration(
            out.join(format!("lab/{}.json", ids[k])),
            &record(s, &room, true),
        )?;
        write_calibration(
            out.join(format!("true/{}.json", ids[k])),
            &record(s, &room, false),
        )?;
        sensors
            .rows
            .push(vec![ids[k].clone(), format!("lab/{}.json", ids[k])]);
        true_rig.push(json!({
            "id": ids[k], "calibration": format!("true/{}.json", ids[k]),
            "world_from_sensor": pose_json(&s.world_from_sensor),
        }));
    }
    sensors.write_to(Some(&out.join("sensors.csv")))?;
    led_table(&wand_names, &room.wand).write_to(Some(&out.join("wand.csv")))?;
    led_table(&frame_names, &room.frame_leds).write_to(Some(&out.join("frame.csv")))?;
    let mut points = Table {
        header: ["frame", "sensor", "led", "x_mm", "y_mm"]
            .map(String::from)
            .to_vec(),
        rows: Vec::with_capacity(room.sightings.len()),
    };
    for s in &room.sightings {
        let led = match s.led {
            RoomLed::Wand(l) => &wand_names[l],
            RoomLed::Frame(l) => &frame_names[l],
        };
        points.rows.push(vec![
            s.frame.to_string(),
            ids[s.sensor].clone(),
            led.clone(),
            num(s.measured.x),
            num(s.measured.y),
        ]);
    }
    points.write_to(Some(&out.join("network_points.csv")))?;
    let mut rig_points = Table {
        header: ["emitter", "sensor", "x_mm", "y_mm"]
            .map(String::from)
            .to_vec(),
        rows: vec![],
    };
    for (e, s, m) in &room.emitter_sightings {
        rig_points.rows.push(vec![
            format!("e{}", e + 1),
            ids[*s].clone(),
            num(m.x),
            num(m.y),
        ]);
    }
    rig_points.write_to(Some(&out.join("rig_points.csv")))?;
    let truth = Table {
        header: ["emitter", "x_mm", "y_mm", "z_mm"]
            .map(String::from)
            .to_vec(),
        rows: room
            .emitters
            .iter()
            .enumerate()
            .map(|(e, p)| vec![format!("e{}", e + 1), num(p.x), num(p.y), num(p.z)])
            .collect(),
    };
    truth.write_to(Some(&out.join("truth.csv")))?;
    let write_json = |name: &str, v: &serde_json::Value| -> Result<()> {
        let text = serde_json::to_string_pretty(v)
            .map_err(|e| Error::Input(format!("cannot encode {name}: {e}")))?;
        Ok(write_atomic_bytes(
            out.join(name),
            (text + "\n").as_bytes(),
        )?)
    };
    write_json(
        "true_rig.json",
        &json!({"format": psdcal_io::RIG_FORMAT, "version": psdcal_io::RIG_VERSION, "sensors": true_rig}),
    )?;
    write_json(
        "network_truth.json",
        &json!({
            "seed": request.seed,
            "point_sigma_mm": room.point_sigma_mm,
            "bad_frames": room.bad_frames,
            "sensors": room.sensors.iter().zip(&ids).map(|(s, id)| json!({
                "id": id, "world_from_sensor": pose_json(&s.world_from_sensor),
                "sensor_from_world": pose_json(&s.world_from_sensor.inverse()),
                "lab": s.lab_params.iter().map(|p| (p.name().to_string(), json!(s.lab.get(*p)))).collect::<serde_json::Map<_, _>>(),
                "truth": s.lab_params.iter().map(|p| (p.name().to_string(), json!(s.truth.get(*p)))).collect::<serde_json::Map<_, _>>(),
            })).collect::<Vec<_>>(),
        }),
    )?;
    folder.finish()?;
    let text =
        format!(
        "Simulated by psdcal {}: a {}×{}×{} mm room, {} sensors (lens 2, each with its own lab \
         error), a {} wand waved {} s at {} Hz ({} frames, {} with a wrong sighting), a static \
         frame of {} LEDs, {} test emitters; {} dB; point noise σ {:.3e} mm; seed {}.\n\
         wrote {}: calibrate with psdcal calibrate-network --sensors sensors.csv --wand wand.csv \
         --frame frame.csv --observations network_points.csv --out rig.json, then locate --rig \
         rig.json rig_points.csv and compare with truth.csv (true_rig.json: the true poses)\n",
        env!("CARGO_PKG_VERSION"),
        options.room_mm[0], options.room_mm[1], options.room_mm[2],
        room.sensors.len(),
        if request.collinear_wand { "collinear 3-LED" } else { "T-shaped 3-LED" },
        request.seconds, request.rate, room.wand_poses.len(), room.bad_frames.len(),
        room.frame_leds.len(), room.emitters.len(), request.snr, room.point_sigma_mm, request.seed,
        out.display()
    );
    Ok(Summary::new(
        text,
        json!({
            "out": out.display().to_string(),
            "sensors": room.sensors.len(),
            "frames": room.wand_poses.len(),
            "bad_frames": room.bad_frames.len(),
            "emitters": room.emitters.len(),
            "point_sigma_mm": room.point_sigma_mm,
        }),
    ))
}
