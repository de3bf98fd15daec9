//! Mutation fuzzing of every reader (docs/formats.md; issue 17): valid
//! files of each format, mutated with a fixed seed (bytes flipped, inserted
//! and deleted, lines repeated, swapped and cut, hostile tokens such as
//! `nan`, `1e999`, quotes, NUL and lone carriage returns spliced in), go
//! through the readers. No input may panic; every error must name the file
//! and be one short line; every accepted file must hold only finite numbers.
//!
//! The number of cases per seed file is `PSDCAL_FUZZ_CASES` (default 150: a
//! few seconds); a release run uses more, e.g.
//! `PSDCAL_FUZZ_CASES=20000 cargo test --release -p psdcal-io --test fuzz`.
//! Every input that once failed is kept in `tests/fuzz_regressions/` and
//! read by every reader on each run. Raw recordings, schedules and tones are
//! fuzzed in `tests/raw.rs`.

use std::path::{Path, PathBuf};

use psdcal_io::{
    read_gains, read_psd_map, read_truth, Calibration, IoError, Observations, PointInput, Points,
    PositionEstimates, PositionTruth, RigFile, RigObservations, Scan, Signals, Template,
};
use psdcal_model::{ChannelGains, PsdGeometry};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The longest error message accepted, characters.
const MAX_MESSAGE: usize = 600;

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn cases() -> usize {
    std::env::var("PSDCAL_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(150)
}

const RIG: &str = r#"{"format": "psdcal-rig", "version": 1, "sensors": [
 {"id": "a", "calibration": "a.json", "world_from_sensor": {"rvec": [0, 0, 0], "t_mm": [0, 0, 0]}},
 {"id": "b", "calibration": "b.json", "sensor_from_world": {"rvec": [3.14, 0, 0], "t_mm": [900, 0, 2600]}}]}"#;
const GAINS: &str = r#"{"format": "psdcal-gains", "version": 1, "method": "equal-current",
 "x2": 1.02, "y1": 0.98, "y2": 1.01, "std": {"g_x2": 1e-4, "g_y1": 1e-4, "g_y2": 2e-4}, "records": 20}"#;
const RIG_POINTS: &str = "emitter,sensor,x_mm,y_mm\ntag1,a,2.68,2.35\ntag1,b,-3.4,-3.8\n\
                          tag2,a,vx,1\n";

/// Checks an error: it names `source` and is one short line.
const POSITION_TRUTH: &str = "emitter,x_mm,y_mm,z_mm,alpha_x_deg,alpha_y_deg\ne1,0,0,0,1,2\n\
    e2,100.5,-200,3,-4,5\n";
const ESTIMATES: &str = "emitter,sensors,x_world_mm,y_world_mm,z_world_mm,sigma_x_world_mm,\
    sigma_y_world_mm,sigma_z_world_mm,cov_xy_world_mm2,cov_xz_world_mm2,cov_yz_world_mm2,status\n\
    e1,a;b,0.5,1,-2,2,3,4,1,0,0,ok\ne2,a,,,,,,,,,,too_few_sensors\n";

fn check_error(source: &str, e: &IoError) {
    let text = e.to_string();
    assert!(
        text.starts_with(source),
        "error does not name the file: {text}"
    );
    assert_eq!(e.file(), Some(source), "{text}");
    assert!(!text.contains('\n'), "multi-line error: {text}");
    assert!(
        text.chars().count() <= MAX_MESSAGE,
        "error of {} characters: {}…",
        text.len(),
        text.chars().take(200).collect::<String>()
    );
}

fn finite(values: impl IntoIterator<Item = f64>) {
    for v in values {
        assert!(v.is_finite(), "a reader accepted a non-finite value");
    }
}

/// Every reader on `bytes`, written to `dir/name`.
fn read_everywhere(dir: &Path, name: &str, bytes: &[u8]) {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let source = path.display().to_string();
    let src = source.as_str();
    match Template::from_reader(src, bytes) {
        Ok(t) => finite(t.leds.iter().flat_map(|l| [l.x_mm, l.y_mm])),
        Err(e) => check_error(src, &e),
    }
    match Observations::from_reader(src, bytes) {
        Ok(o) => finite(o.rows.iter().flat_map(|r| [r.x_mm, r.y_mm])),
        Err(e) => check_error(src, &e),
    }
    match Signals::from_reader(src, bytes) {
        Ok(s) => finite(s.rows.iter().flat_map(|r| [r.vx1, r.vx2, r.vy1, r.vy2])),
        Err(e) => check_error(src, &e),
    }
    match Points::read(&path) {
        Ok(p) => {
            for row in &p.rows {
                match &row.input {
                    PointInput::Position(q) => finite([q.x, q.y]),
                    PointInput::Amplitudes(a) => finite([a.vx1, a.vx2, a.vy1, a.vy2]),
                    _ => {}
                }
            }
        }
        Err(e) => check_error(src, &e),
    }
    match RigObservations::from_reader(src, bytes) {
        Ok(o) => {
            for row in &o.rows {
                if let PointInput::Position(q) = &row.input {
                    finite([q.x, q.y]);
                }
            }
        }
        Err(e) => check_error(src, &e),
    }
    match Calibration::from_json_bytes(src, bytes) {
        Ok(c) => finite([c.intrinsics.f_mm, c.sensor.lx_mm, c.sensor.ly_mm]),
        Err(e) => check_error(src, &e),
    }
    match read_gains(&path) {
        Ok(g) => finite([g.x2, g.y1, g.y2, g.std.g_x2, g.std.g_y1, g.std.g_y2]),
        Err(e) => check_error(src, &e),
    }
    if let Ok(text) = std::str::from_utf8(bytes) {
        if let Err(e) = RigFile::from_json_str(src, text, dir) {
            check_error(src, &e);
        }
    }
    if let Err(e) = read_truth(&path) {
        check_error(src, &e);
    }
    match Scan::from_reader(src, bytes) {
        Ok(scan) => match scan.points(&PsdGeometry::default(), &ChannelGains::UNIT) {
            Ok(p) => finite(p.stage.iter().chain(&p.measured).flat_map(|q| [q.x, q.y])),
            Err(e) => check_error(src, &e),
        },
        Err(e) => check_error(src, &e),
    }
    match read_psd_map(&path) {
        Ok((_, map)) => finite(map.block.iter().copied()),
        Err(e) => check_error(src, &e),
    }
    match PositionTruth::read(&path) {
        Ok(t) => finite(t.rows.iter().flat_map(|r| {
            let p = r.position.map_or([0.0; 3], |p| [p.x, p.y, p.z]);
            let a = r.alpha.map_or([0.0; 2], |a| [a.x, a.y]);
            p.into_iter().chain(a)
        })),
        Err(e) => check_error(src, &e),
    }
    match PositionEstimates::read(&path) {
        Ok(est) => {
            for r in &est.rows {
                finite(r.position.iter().flat_map(|p| [p.x, p.y, p.z]));
                finite(r.position_covariance.iter().flat_map(|c| c.iter().copied()));
                finite(r.alpha.iter().flat_map(|a| [a.x, a.y]));
            }
        }
        Err(e) => check_error(src, &e),
    }
}

const SCAN: &str =
    "x_stage_mm,y_stage_mm,x_mm,y_mm\n0,0,0.001,0\n1,0,0.998,0.002\n0,1,0,0.997\n1,1,0.996,0.995\n";

const PSD_MAP: &str = r#"{"format": "psdcal-psd-map", "version": 1,
"sensor": {"lx_mm": 9.0, "ly_mm": 9.0}, "model": "poly:1",
"stage": {"basis": "polynomial", "order": 1, "frame_mm": [-4.5, -4.5, 4.5, 4.5],
  "hull_mm": [[-4.5, -4.5], [4.5, -4.5], [4.5, 4.5], [-4.5, 4.5]]},
"coefficients": {"x": [0.001, -0.002, 0.0], "y": [0.0, 0.0, 0.003]},
"covariance": {"sigma_x_mm": 0.0003, "sigma_y_mm": 0.0003,
  "unit": [[0.01, 0.0, 0.0], [0.0, 0.02, 0.0], [0.0, 0.0, 0.02]]},
"fit": {"points": 9, "from_amplitudes": false, "rejected_lines": [], "folds": 5,
  "cv_rms_um": 0.5, "rms_um": 0.4, "sigma_x_um": 0.3, "sigma_y_um": 0.3,
  "map_sigma_um": 0.05, "effective_terms": 3.0,
  "candidates": [{"model": "poly:1", "cv_rms_um": 0.5}]},
"residuals": {"x_mm": [0.0], "y_mm": [0.0], "dx_um": [0.1], "dy_um": [-0.1]},
"provenance": {"psdcal_version": "0.1.0", "command": "", "options": {}, "inputs": [],
  "created_utc": "2026-12-01T00:00:00Z"}}
"#;

const TOKENS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e999",
    "-1e999",
    "1e308",
    "4.9e-324",
    "0",
    "-0",
    "\"",
    "\"\"",
    ",",
    ",,",
    ";",
    "\t",
    "\r",
    "\r\n",
    "\n",
    "\0",
    "\u{feff}",
    "é",
    "#",
    "{",
    "}",
    "[",
    "]",
    "null",
    "true",
    "\"version\": 99",
    "99999999999999999999999",
    "x_mm",
    "vx1",
    "led",
    "image",
];

/// One mutation of `seed`.
fn mutate(seed: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..rng.random_range(1..4) {
        let len = b.len().max(1);
        let at = rng.random_range(0..len).min(b.len());
        match rng.random_range(0..8) {
            0 if !b.is_empty() => {
                let i = at.min(b.len() - 1);
                b[i] ^= 1 << rng.random_range(0..8);
            }
            1 => {
                let token = TOKENS[rng.random_range(0..TOKENS.len())];
                b.splice(at..at, token.bytes());
            }
            2 => {
                let end = (at + rng.random_range(1..40)).min(b.len());
                b.drain(at..end);
            }
            3 => b.truncate(at),
            4 => {
                // Repeat a line many times.
                let text = String::from_utf8_lossy(&b).into_owned();
                let lines: Vec<&str> = text.lines().collect();
                if let Some(line) = lines.get(rng.random_range(0..lines.len().max(1))) {
                    let extra = format!("{line}\n").repeat(rng.random_range(1..50));
                    b.splice(at..at, extra.bytes());
                }
            }
            5 => {
                let text = String::from_utf8_lossy(&b).into_owned();
                let mut lines: Vec<&str> = text.lines().collect();
                if lines.len() > 1 {
                    let i = rng.random_range(0..lines.len());
                    let j = rng.random_range(0..lines.len());
                    lines.swap(i, j);
                    b = lines.join("\n").into_bytes();
                }
            }
            6 => {
                let byte = rng.random::<u8>();
                b.insert(at, byte);
            }
            _ => {
                let digits = "9".repeat(rng.random_range(1..400));
                b.splice(at..at, digits.bytes());
            }
        }
    }
    b
}

fn seeds() -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for dir in ["data/example", "crates/psdcal-cli/tests/data/valid"] {
        let dir = workspace().join(dir);
        let mut entries: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for path in entries {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            out.push((name, std::fs::read(&path).unwrap()));
        }
    }
    out.push(("rig.json".into(), RIG.as_bytes().to_vec()));
    out.push(("gains.json".into(), GAINS.as_bytes().to_vec()));
    out.push(("rig_points.csv".into(), RIG_POINTS.as_bytes().to_vec()));
    out.push(("scan.csv".into(), SCAN.as_bytes().to_vec()));
    out.push(("psd_map.json".into(), PSD_MAP.as_bytes().to_vec()));
    out.push(("truth.csv".into(), POSITION_TRUTH.as_bytes().to_vec()));
    out.push(("estimates.csv".into(), ESTIMATES.as_bytes().to_vec()));
    out
}

#[test]
fn mutated_files_never_panic_and_errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    for (name, seed) in seeds() {
        read_everywhere(dir.path(), &name, &seed);
        for _ in 0..cases() {
            let mutated = mutate(&seed, &mut rng);
            read_everywhere(dir.path(), &name, &mutated);
        }
    }
}

#[test]
fn regression_inputs_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let mut n = 0;
    for entry in std::fs::read_dir(corpus).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        read_everywhere(dir.path(), &name, &std::fs::read(&path).unwrap());
        n += 1;
    }
    assert!(n >= 3, "the regression corpus is missing");
}

#[test]
fn huge_cr_only_file_gives_a_short_error() {
    // Issue 17: a CR-only file of several MiB used to echo its whole
    // "header line" in the message.
    let mut bytes = b"x_mm,y_mm\r".to_vec();
    bytes.extend(b"1.25,2.5\r".repeat(300_000));
    let e = Points::from_reader("cr.csv", &bytes[..]).unwrap_err();
    check_error("cr.csv", &e);
    assert!(e.to_string().contains("carriage return alone"), "{e}");
}
