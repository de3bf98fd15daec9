//! Shared helpers of the CLI integration tests: running the binary, and the
//! generator of the valid fixtures in `tests/data/valid/`.
//!
//! The fixtures are real model output: the template seen by the paper's lens
//! 2 (`SensorModel::paper_lens2()`) in four poses, projected with
//! `Model::project_to_tolerance`. `tests/cli.rs` checks that the committed files
//! equal what [`valid_fixtures`] generates; run the tests with
//! `PSDCAL_BLESS=1` to rewrite them after changing the generator.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use nalgebra::{Vector2, Vector3};
use psdcal_io::{Calibration, CostKind, Covariance, FitSummary, GainsRecord, ImageFit, StdDevs};
use psdcal_model::psd::{electrode_currents, is_on_active_area};
use psdcal_model::{ChannelGains, Param, Pose, PsdGeometry, SensorModel};

/// Runs `psdcal` with `args`.
pub fn psdcal<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    Command::new(env!("CARGO_BIN_EXE_psdcal"))
        .args(args)
        .output()
        .expect("the psdcal binary runs")
}

/// A simulated data set with the PSD's non-linearity (`dir/sim`: lens 2,
/// 40 dB), a lensless scan of a sensor (`dir/scan.csv`: 0.5 mm steps,
/// 50 dB) and its map (`dir/map.json`, `psd-map` given `map_args` too):
/// `(sim, scan, map)`.
pub fn simulated_map(dir: &Path, map_args: &[&str]) -> (PathBuf, PathBuf, PathBuf) {
    let (sim, scan, map) = (dir.join("sim"), dir.join("scan.csv"), dir.join("map.json"));
    let text = |p: &Path| p.to_str().unwrap().to_owned();
    let (sim_text, scan_text, map_text) = (text(&sim), text(&scan), text(&map));
    let mut psd_map = vec!["psd-map", "--scan", &scan_text, "-q", "--out", &map_text];
    psd_map.extend_from_slice(map_args);
    for args in [
        vec![
            "simulate",
            "--lens",
            "2",
            "--snr",
            "40",
            "--psd-nonlinearity",
            "-q",
            "--out",
            &sim_text,
        ],
        vec![
            "simulate-scan",
            "--step",
            "0.5",
            "--snr",
            "50",
            "-q",
            "--out",
            &scan_text,
        ],
        psd_map,
    ] {
        let out = psdcal(&args);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
    }
    (sim, scan, map)
}

/// Standard output as text.
pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// Standard error as text.
pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// `tests/data/<sub>`.
pub fn data_dir(sub: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("data")
        .join(sub)
}

/// A valid fixture's path.
pub fn valid(name: &str) -> PathBuf {
    data_dir("valid").join(name)
}

/// The sensor model of the fixtures.
pub fn model() -> SensorModel {
    SensorModel::paper_lens2()
}

/// The channel gains stored in the fixture calibration.
pub fn gains() -> ChannelGains {
    ChannelGains {
        x2: 1.02,
        y1: 0.98,
        y2: 1.01,
    }
}

/// The template: 14 LEDs, a 5-4-5 grid with 100 mm pitch; three row lines
/// and four column lines (the fifth column has only two LEDs).
pub fn template_leds() -> Vec<(String, f64, f64, String)> {
    let mut leds = Vec::new();
    let mut id = 1;
    for (row, y) in [(1, -100.0), (2, 0.0), (3, 100.0)] {
        let columns: &[i32] = if row == 2 {
            &[1, 2, 3, 4]
        } else {
            &[1, 2, 3, 4, 5]
        };
        for &column in columns {
            let x = -200.0 + 100.0 * f64::from(column - 1);
            let lines = if column <= 4 {
                format!("r{row};c{column}")
            } else {
                format!("r{row}")
            };
            leds.push((id.to_string(), x, y, lines));
            id += 1;
        }
    }
    leds
}

/// The four template poses (sensor from template).
pub fn poses() -> Vec<(String, Pose)> {
    [
        ([0.10, -0.12, 0.05], [-120.0, -90.0, 800.0]),
        ([-0.15, 0.20, -0.10], [110.0, 80.0, 900.0]),
        ([0.20, 0.15, 0.30], [60.0, -140.0, 1000.0]),
        ([0.0, 0.0, -0.20], [-90.0, 140.0, 850.0]),
    ]
    .into_iter()
    .enumerate()
    .map(|(i, (r, t))| {
        (
            format!("pose{}", i + 1),
            Pose::new(Vector3::from(r), Vector3::from(t)),
        )
    })
    .collect()
}

/// Measured points of every (image, LED), in file order.
pub fn measured_points() -> Vec<(String, String, Vector2<f64>)> {
    let model = psdcal_model::Model::standard(&model());
    let geometry = PsdGeometry::default();
    let mut rows = Vec::new();
    for (image, pose) in poses() {
        for (led, x, y, _) in template_leds() {
            let m = model
                .project_to_tolerance(&pose, &Vector2::new(x, y))
                .expect("fixture points project");
            assert!(
                is_on_active_area(&geometry, &m),
                "fixture point off the sensor: {image} {led} {m:?}"
            );
            rows.push((image.clone(), led, m));
        }
    }
    rows
}

/// Points to correct: some measured points, with text columns around them.
pub fn points_to_correct() -> Vec<Vector2<f64>> {
    measured_points()
        .into_iter()
        .step_by(7)
        .map(|(_, _, p)| p)
        .chain([Vector2::new(0.0, 0.0), Vector2::new(-4.25, 4.5)])
        .collect()
}

fn calibration() -> Calibration {
    let mut cal = Calibration::from_model(&model(), &PsdGeometry::default());
    let estimated = [Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2];
    cal.set_estimated(&estimated);
    cal.gains = Some(GainsRecord::new(&gains(), false));
    let std = [2e-3, 1e-3, 1e-3, 4e-5, 2e-7];
    cal.std = StdDevs(
        estimated
            .iter()
            .zip(std)
            .map(|(p, s)| (p.name().to_string(), s))
            .collect(),
    );
    cal.covariance = Covariance {
        parameters: estimated.iter().map(|p| p.name().to_string()).collect(),
        matrix: (0..estimated.len())
            .map(|i| {
                (0..estimated.len())
                    .map(|j| if i == j { std[i] * std[i] } else { 0.0 })
                    .collect()
            })
            .collect(),
    };
    let points = measured_points().len();
    cal.fit = FitSummary {
        cost: CostKind::Template,
        residual_mm2: 0.0,
        rms_template_mm: 0.0,
        rms_image_mm: 0.0,
        iterations: 0,
        points,
        images: poses().len(),
        termination: "fixture written from the true model".to_string(),
        ..FitSummary::default()
    };
    cal.images = poses()
        .iter()
        .map(|(id, pose)| ImageFit::new(id, pose, 0.0, template_leds().len()))
        .collect();
    cal
}

/// Every valid fixture: (file name, content).
pub fn valid_fixtures() -> Vec<(&'static str, String)> {
    let mut template = String::from(
        "# Test template: 14 LEDs, 100 mm pitch, rows r1-r3 and columns c1-c4.\nled,X_mm,Y_mm,lines\n",
    );
    for (id, x, y, lines) in template_leds() {
        template.push_str(&format!("{id},{x},{y},{lines}\n"));
    }
    let header = "# Noise-free measured points of SensorModel::paper_lens2() in four poses\n\
                  # (tests/common/mod.rs).\n";
    let mut observations = format!("{header}image,led,x_mm,y_mm\n");
    let mut signals = format!("{header}image,led,vx1,vx2,vy1,vy2\n");
    let geometry = PsdGeometry::default();
    for (image, led, m) in measured_points() {
        observations.push_str(&format!("{image},{led},{},{}\n", m.x, m.y));
        let a = electrode_currents(&geometry, &m, 1.0);
        signals.push_str(&format!(
            "{image},{led},{},{},{},{}\n",
            a.vx1, a.vx2, a.vy1, a.vy2
        ));
    }
    let mut points = String::from("# Points to correct.\nid,note,x_mm,y_mm,extra\n");
    let mut amplitudes =
        String::from("# Amplitudes through the calibration's gains.\nvx1,vx2,vy1,vy2,tag\n");
    for (k, p) in points_to_correct().iter().enumerate() {
        points.push_str(&format!("p{k},\"note, {k}\",{},{}, x \n", p.x, p.y));
        let a = electrode_currents(&geometry, p, 2.0).apply_gains(&gains());
        amplitudes.push_str(&format!("{},{},{},{},t{k}\n", a.vx1, a.vx2, a.vy1, a.vy2));
    }
    let calibration = calibration()
        .to_json_string("calibration.json")
        .expect("fixture calibration is valid");
    vec![
        ("template.csv", template),
        ("observations.csv", observations),
        ("signals.csv", signals),
        ("points.csv", points),
        ("points_amplitudes.csv", amplitudes),
        ("calibration.json", calibration),
    ]
}
