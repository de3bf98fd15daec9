//! `psdcal calibrate-in-situ` end to end: surveyed emitters in a room (a
//! template.csv with Z_mm) seen by the paper's lens 2 in two orientations,
//! noise-free, projected here through the model independently of the
//! calibration; the fit gives the true intrinsics, the poses file is
//! written, and bad input is refused.

mod common;

use common::{psdcal, stderr};
use nalgebra::{Vector2, Vector3};
use psdcal_model::{Model, Pose, SensorModel};

/// Emitters 2–5 m in front of the sensor, spread over its field of view
/// (a fixed low-discrepancy pattern, no random draw).
fn emitters() -> Vec<Vector3<f64>> {
    (0..20)
        .map(|k| {
            let (u, v) = (
                (k as f64 * 0.618_034).fract(),
                (k as f64 * 0.754_877).fract(),
            );
            let z = 2000.0 + 3000.0 * ((k as f64 * 0.569_840).fract());
            Vector3::new((u - 0.5) * 0.6 * z, (v - 0.5) * 0.6 * z, z)
        })
        .collect()
}

#[test]
fn a_room_of_surveyed_emitters_gives_the_true_intrinsics() {
    let truth = SensorModel::paper_lens2();
    let model = Model::standard(&truth);
    let orientations = [
        Pose::new(Vector3::new(0.0, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.0)),
        Pose::new(
            Vector3::new(0.05, -0.08, 0.02),
            Vector3::new(30.0, -20.0, 50.0),
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    let mut template = String::from("led,X_mm,Y_mm,Z_mm\n");
    let mut observations = String::from("image,led,x_mm,y_mm\n");
    for (k, p) in emitters().iter().enumerate() {
        template.push_str(&format!("e{k},{},{},{}\n", p.x, p.y, p.z));
        for (i, pose) in orientations.iter().enumerate() {
            let m: Vector2<f64> = model.project_point(pose, p).unwrap();
            if m.x.abs() < 4.4 && m.y.abs() < 4.4 {
                observations.push_str(&format!("o{i},e{k},{},{}\n", m.x, m.y));
            }
        }
    }
    let (t, o) = (dir.path().join("emitters.csv"), dir.path().join("obs.csv"));
    std::fs::write(&t, template).unwrap();
    std::fs::write(&o, observations).unwrap();
    let (cal, poses) = (dir.path().join("cal.json"), dir.path().join("pose.json"));
    let run = psdcal([
        "-q".as_ref(),
        "calibrate-in-situ".as_ref(),
        "-t".as_ref(),
        t.as_os_str(),
        "-o".as_ref(),
        o.as_os_str(),
        "--out".as_ref(),
        cal.as_os_str(),
        "--poses-out".as_ref(),
        poses.as_os_str(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let record = psdcal_io::read_calibration(&cal).unwrap();
    // Noise-free data: the fit is exact up to the solver's tolerance.
    assert!((record.intrinsics.f_mm - truth.intrinsics.f).abs() < 1e-6);
    assert!((record.intrinsics.cx_mm - truth.intrinsics.cx).abs() < 1e-6);
    assert!(std::fs::read_to_string(&poses)
        .unwrap()
        .contains("sensor_from_world"));
    // A negative side of the active area is a usage error (exit 2).
    let bad = psdcal([
        "calibrate-in-situ".as_ref(),
        "-t".as_ref(),
        t.as_os_str(),
        "-o".as_ref(),
        o.as_os_str(),
        "--lx".as_ref(),
        "-1".as_ref(),
        "--out".as_ref(),
        cal.as_os_str(),
    ]);
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
}
