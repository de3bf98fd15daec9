//! `track --rig` against a simulated rig with known truth: simulate-positioning
//! gives calibrated sensors with known poses and emitter positions; the
//! test builds, independently of `track`, the stream a card sampling every
//! sensor would record (each emitter at its own tone, its amplitudes from
//! its true position through the rig's calibrated models and the
//! pin-cushion forward model) and checks that `track` gives the emitters'
//! positions: to 1e-4 mm without noise, and at 50 dB per channel within the
//! reported covariance (the 95 % ellipsoid holds 0.95 ± 0.06 of the
//! windows).

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;

use nalgebra::{Matrix3, Vector2, Vector3};
use psdcal::{
    simulate_positioning, DemodConfig, Lens, LoadedSensor, PositioningRequest, RoomOptions,
    TrackRequest, TrackTarget,
};
use psdcal_io::{read_rig, PositionTruth};
use psdcal_model::psd::electrode_currents;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const FS: f64 = 20_000.0;
const TONES: [f64; 3] = [900.0, 1100.0, 1300.0];

/// The rig, its emitters' truth, and per sensor and emitter the amplitudes.
struct Scene {
    ids: Vec<String>,
    truth: Vec<Vector3<f64>>,
    /// `amps[s][e]`: vx1, vx2, vy1, vy2.
    amps: Vec<Vec<[f64; 4]>>,
}

fn scene(dir: &Path) -> Scene {
    let room = RoomOptions {
        sensors: 3,
        emitters: 3,
        ..RoomOptions::default()
    };
    simulate_positioning(&PositioningRequest {
        lens: Lens::Two,
        snr_db: None,
        images: 9,
        record_cycles: 65,
        room,
        seed: 5,
        out: dir.to_path_buf(),
        force: false,
    })
    .unwrap();
    let rig = read_rig(dir.join("rig.json")).unwrap();
    let truth = PositionTruth::read(dir.join("truth.csv")).unwrap();
    let truth: Vec<Vector3<f64>> = truth.rows.iter().map(|r| r.position.unwrap()).collect();
    let mut amps = Vec::new();
    for s in &rig.sensors {
        let loaded = LoadedSensor::read(&s.calibration_path).unwrap();
        let sensor = &loaded.sensor;
        let pose = &s.world_from_sensor;
        let r = pose.rotation();
        let model = psdcal_model::Model::standard(&sensor.model);
        amps.push(
            truth
                .iter()
                .map(|p| {
                    let q: Vector3<f64> = r.transpose() * (p - pose.t);
                    let m = psdcal_locate::measured_from_ray(
                        &model,
                        &Vector2::new(q.x / q.z, q.y / q.z),
                    )
                    .unwrap();
                    let a = electrode_currents(&sensor.geometry, &m, 1.0);
                    [a.vx1, a.vx2, a.vy1, a.vy2]
                })
                .collect(),
        );
    }
    Scene {
        ids: rig.sensors.iter().map(|s| s.id.clone()).collect(),
        truth,
        amps,
    }
}

/// The CSV stream of every sensor's channels; white noise of `sigma` V.
fn stream(scene: &Scene, samples: usize, sigma: f64, seed: u64) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Box–Muller: one standard normal per call.
    let noise = move |rng: &mut ChaCha8Rng| {
        let u: f64 = 1.0 - rng.random::<f64>();
        let v: f64 = rng.random::<f64>();
        sigma * (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
    };
    let mut out = String::new();
    let names: Vec<String> = scene
        .ids
        .iter()
        .flat_map(|s| ["vx1", "vx2", "vy1", "vy2"].map(|c| format!("{s}/{c}")))
        .collect();
    out += &names.join(",");
    out.push('\n');
    for n in 0..samples {
        let t = n as f64 / FS;
        let mut fields = Vec::with_capacity(names.len());
        for sensor in &scene.amps {
            for c in 0..4 {
                let mut v: f64 = sensor
                    .iter()
                    .zip(TONES)
                    .map(|(a, f)| a[c] * (2.0 * PI * f * t + 0.3).sin())
                    .sum();
                if sigma > 0.0 {
                    v += noise(&mut rng);
                }
                fields.push(v);
            }
        }
        let _ = writeln!(
            out,
            "{}",
            fields
                .iter()
                .map(|v| format!("{v:e}"))
                .collect::<Vec<_>>()
                .join(",")
        );
    }
    out
}

fn run(dir: &Path, text: &str) -> Vec<Vec<String>> {
    let mut tones = String::from("led,frequency_hz\n");
    for (e, f) in TONES.iter().enumerate() {
        tones += &format!("e{},{f}\n", e + 1);
    }
    std::fs::write(dir.join("tones.csv"), tones).unwrap();
    let mut out = Vec::new();
    psdcal::track(
        &TrackRequest {
            target: TrackTarget::Rig(dir.join("rig.json")),
            rate_hz: Some(FS),
            tones: dir.join("tones.csv"),
            window_s: 0.05,
            config: DemodConfig::default(),
            raw: None,
            channels: Vec::new(),
            limits: Default::default(),
            filter: Default::default(),
        },
        text.as_bytes(),
        &mut out,
    )
    .unwrap();
    let out = String::from_utf8(out).unwrap();
    let mut lines = out.lines();
    assert!(lines
        .next()
        .unwrap()
        .starts_with("t_s,led,sensors,x_world_mm"));
    lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect()
}

fn position(row: &[String]) -> (Vector3<f64>, Matrix3<f64>) {
    let v = |i: usize| row[i].parse::<f64>().unwrap();
    let p = Vector3::new(v(3), v(4), v(5));
    let (sx, sy, sz) = (v(6), v(7), v(8));
    let c = Matrix3::new(
        sx * sx,
        v(9),
        v(10),
        v(9),
        sy * sy,
        v(11),
        v(10),
        v(11),
        sz * sz,
    );
    (p, c)
}

#[test]
fn rig_positions_match_the_truth_and_their_covariance() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = scene(d);
    // Noise free: 4 windows × 3 emitters, each at its true position.
    let rows = run(d, &stream(&scene, 4000, 0.0, 1));
    assert_eq!(rows.len(), 12);
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(row[14], "ok", "{row:?}");
        assert_eq!(row[2], scene.ids.join(";"));
        let e = i % 3;
        assert_eq!(row[1], format!("e{}", e + 1));
        let (p, _) = position(row);
        assert!(
            (p - scene.truth[e]).norm() < 1e-4,
            "{row:?} vs {}",
            scene.truth[e]
        );
    }
    // 50 dB per channel for the weakest amplitude: the error against the
    // reported covariance over 40 windows × 3 emitters.
    let weakest = scene
        .amps
        .iter()
        .flatten()
        .flatten()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let sigma = weakest / 2f64.sqrt() * 10f64.powf(-50.0 / 20.0);
    let rows = run(d, &stream(&scene, 40_000, sigma, 2));
    assert_eq!(rows.len(), 120);
    let mut inside = 0;
    let mut mean_error = 0.0;
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(row[14], "ok", "{row:?}");
        let (p, c) = position(row);
        let err = p - scene.truth[i % 3];
        mean_error += err.norm() / rows.len() as f64;
        let d2 = err.dot(&(c.try_inverse().unwrap() * err));
        if d2 <= 7.814_727_903_251_178 {
            inside += 1;
        }
    }
    let fraction = inside as f64 / rows.len() as f64;
    assert!(
        (0.89..=1.0).contains(&fraction),
        "inside the 95 % ellipsoid: {fraction}; mean error {mean_error} mm"
    );
    assert!(
        mean_error > 1e-4,
        "noise must move the positions: {mean_error}"
    );
}

/// `track`'s output text for the request's recording file `raw` (or the
/// `stdin` text when `raw` is `None`).
fn track_text(dir: &Path, raw: Option<&Path>, rate: Option<f64>, stdin: &str) -> String {
    let mut out = Vec::new();
    psdcal::track(
        &TrackRequest {
            target: TrackTarget::Rig(dir.join("rig.json")),
            rate_hz: rate,
            tones: dir.join("tones.csv"),
            window_s: 0.05,
            config: DemodConfig::default(),
            raw: raw.map(Path::to_path_buf),
            channels: Vec::new(),
            limits: Default::default(),
            filter: Default::default(),
        },
        stdin.as_bytes(),
        &mut out,
    )
    .unwrap();
    String::from_utf8(out).unwrap()
}

/// The rig's recording as raw.csv (with `t_s`, columns shuffled), raw.npy
/// (`4 S` columns, rig.json's order) and raw.tdms (a group per sensor) gives
/// the same rows as the same samples on standard input.
#[test]
fn every_raw_format_gives_the_rows_of_the_stream() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = scene(d);
    let text = stream(&scene, 3000, 1e-4, 3);
    let reference = {
        run(d, &text); // writes tones.csv
        track_text(d, None, Some(FS), &text)
    };
    assert_eq!(reference.lines().count(), 1 + 3 * 3);
    let mut lines = text.lines();
    let names: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // raw.csv: t_s first, the sensors in reverse order; the rate from t_s.
    let width = names.len();
    let order: Vec<usize> = (0..width / 4)
        .rev()
        .flat_map(|s| (0..4).map(move |c| 4 * s + c))
        .collect();
    let mut csv = String::from("t_s");
    for &i in &order {
        csv += &format!(",{}", names[i]);
    }
    csv.push('\n');
    for (n, r) in rows.iter().enumerate() {
        csv += &psdcal_io::number_text(n as f64 / FS);
        for &i in &order {
            csv += &format!(",{:e}", r[i]);
        }
        csv.push('\n');
    }
    std::fs::write(d.join("raw.csv"), csv).unwrap();
    assert_eq!(track_text(d, Some(&d.join("raw.csv")), None, ""), reference);
    // raw.npy of 4 S columns.
    let mut npy = psdcal_io::npy_header_columns(rows.len() as u64, width as u64);
    for r in &rows {
        for v in r {
            npy.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(d.join("raw.npy"), npy).unwrap();
    assert_eq!(
        track_text(d, Some(&d.join("raw.npy")), Some(FS), ""),
        reference
    );
    // raw.tdms, a group per sensor, in two segments.
    let mut writer = psdcal_io::TdmsFrameWriter::with_groups(FS, scene.ids.clone());
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    let mut tdms = Vec::new();
    writer.write_rows(&mut tdms, &flat[..1000 * width]).unwrap();
    writer.write_rows(&mut tdms, &flat[1000 * width..]).unwrap();
    std::fs::write(d.join("raw.tdms"), tdms).unwrap();
    assert_eq!(
        track_text(d, Some(&d.join("raw.tdms")), None, ""),
        reference
    );
    // A raw.npy of the wrong width is refused, naming the shape.
    let bad = psdcal_io::npy_header_columns(1, 4);
    std::fs::write(d.join("bad.npy"), [bad, vec![0; 32]].concat()).unwrap();
    let err = psdcal::track(
        &TrackRequest {
            target: TrackTarget::Rig(d.join("rig.json")),
            rate_hz: Some(FS),
            tones: d.join("tones.csv"),
            window_s: 0.05,
            config: DemodConfig::default(),
            raw: Some(d.join("bad.npy")),
            channels: Vec::new(),
            limits: Default::default(),
            filter: Default::default(),
        },
        "".as_bytes(),
        Vec::new(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("expected (N, 12)"), "{err}");
}
