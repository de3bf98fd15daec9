//! Writes the small example data set shipped in `data/example/`: the paper's
//! lens 2 (docs/model.md §7) seen through nine noise-free poses of a 14-LED
//! template with unaligned LEDs (docs/cli.md's `check` and `calibrate`
//! examples run on it).
//!
//! Run from the repository root: `cargo run -p psdcal-model --example make_example_data`.

use std::fmt::Write as _;

use nalgebra::{Vector2, Vector3};
use psdcal_model::paper_setup::SCATTER14_MM;
use psdcal_model::psd::{electrode_currents, is_on_active_area, transimpedance_gain};
use psdcal_model::{Model, Pose, PsdGeometry, SensorModel};

/// LED positions on the template (mm): `scatter14`, 14 LEDs, no three
/// collinear (the paper's set-up as psdcal fixes it).
const TEMPLATE_MM: [(f64, f64); 14] = SCATTER14_MM;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let model = SensorModel::paper_lens2();
    let chain = Model::standard(&model);
    let geometry = PsdGeometry::default();
    // Nine poses: the template's centre aimed at a 3 × 3 grid of sensor
    // positions, 0.7–1.5 m away, tilted up to about 30°.
    let aims = [-3.1, 0.0, 3.1];
    let depths = [
        700.0, 1100.0, 1500.0, 900.0, 1300.0, 800.0, 1000.0, 1400.0, 1200.0,
    ];
    let tilts = [
        (0.30, -0.20, 0.10),
        (-0.25, 0.35, -0.40),
        (0.45, 0.10, 0.70),
        (-0.40, -0.30, 1.20),
        (0.05, 0.50, -0.90),
        (0.35, 0.35, 2.00),
        (-0.50, 0.00, -1.60),
        (0.20, -0.45, 2.80),
        (-0.10, 0.25, 0.30),
    ];
    let mut poses = Vec::new();
    for (k, (&z, &(rx, ry, rz))) in depths.iter().zip(tilts.iter()).enumerate() {
        let (u, v) = (aims[k % 3], aims[k / 3]);
        let t = Vector3::new(
            (u - model.intrinsics.cx) * z / model.intrinsics.f,
            (v - model.intrinsics.cy) * z / model.intrinsics.f,
            z,
        );
        poses.push(Pose::new(Vector3::new(rx, ry, rz), t));
    }

    let mut template =
        String::from("# Example calibration template: 14 LEDs, unaligned (mm).\nled,X_mm,Y_mm\n");
    for (i, (x, y)) in TEMPLATE_MM.iter().enumerate() {
        writeln!(template, "{},{x},{y}", i + 1)?;
    }
    let mut observations = String::from(
        "# Noise-free impact points of the paper's lens 2 (f = 8 mm, k1 = 1e-2, k2 = 3e-5,\n\
         # centre (0.5, -0.7) mm), nine template poses. Written by make_example_data.\n\
         image,led,x_mm,y_mm\n",
    );
    let mut signals = String::from(
        "# Electrode amplitudes (V) of the same points: 20 uA photocurrent, balanced\n\
         # transimpedance gain K = R/(2 pi f R C + 1), R = 100 kOhm, C = 100 pF, 1 kHz.\n\
         image,led,vx1,vx2,vy1,vy2\n",
    );
    let gain = transimpedance_gain(100e3, 100e-12, 1e3);
    for (k, pose) in poses.iter().enumerate() {
        for (i, (x, y)) in TEMPLATE_MM.iter().enumerate() {
            let m = chain.project_to_tolerance(pose, &Vector2::new(*x, *y))?;
            let margin = 4.5 - m.x.abs().max(m.y.abs());
            if !is_on_active_area(&geometry, &m) || margin < 0.05 {
                return Err(format!(
                    "image {} LED {} falls at {m:?}, too near the edge",
                    k + 1,
                    i + 1
                )
                .into());
            }
            writeln!(
                observations,
                "{},{},{:.15e},{:.15e}",
                k + 1,
                i + 1,
                m.x,
                m.y
            )?;
            let a = electrode_currents(&geometry, &m, 20e-6);
            writeln!(
                signals,
                "{},{},{:.15e},{:.15e},{:.15e},{:.15e}",
                k + 1,
                i + 1,
                a.vx1 * gain,
                a.vx2 * gain,
                a.vy1 * gain,
                a.vy2 * gain
            )?;
        }
    }
    let mut truth = String::from("# image,rx,ry,rz,tx_mm,ty_mm,tz_mm: the true sensor_from_template poses.\nimage,rx,ry,rz,tx_mm,ty_mm,tz_mm\n");
    for (k, p) in poses.iter().enumerate() {
        let a = p.to_array();
        writeln!(
            truth,
            "{},{},{},{},{},{},{}",
            k + 1,
            a[0],
            a[1],
            a[2],
            a[3],
            a[4],
            a[5]
        )?;
    }
    std::fs::write("data/example/template.csv", template)?;
    std::fs::write("data/example/observations.csv", observations)?;
    std::fs::write("data/example/signals.csv", signals)?;
    std::fs::write("data/example/poses_truth.csv", truth)?;
    println!("wrote data/example/{{template,observations,signals,poses_truth}}.csv");
    Ok(())
}
