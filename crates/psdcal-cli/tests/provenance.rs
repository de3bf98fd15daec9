//! Provenance: every input file a result was made from is listed once, in
//! the order read, with the SHA-256 of its bytes — psd_map.json (its scan),
//! and calibration.json with a PSD map (template, points, map). The hashes
//! are checked against the files' bytes hashed apart from the job, and
//! against the published SHA-256 test vector.

mod common;

use std::path::Path;

use common::{psdcal, stderr};
use serde_json::Value;

fn run_ok(args: &[&str]) {
    let out = psdcal(args);
    assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The `(path, sha256)` pairs of a file's `provenance.inputs`.
fn inputs(file: &Value) -> Vec<(String, String)> {
    file["provenance"]["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| {
            (
                i["path"].as_str().unwrap().to_string(),
                i["sha256"].as_str().unwrap().to_string(),
            )
        })
        .collect()
}

fn expected(paths: &[&Path]) -> Vec<(String, String)> {
    paths
        .iter()
        .map(|p| {
            (
                p.display().to_string(),
                psdcal::sha256_hex(&std::fs::read(p).unwrap()),
            )
        })
        .collect()
}

#[test]
fn the_hash_function_is_sha256() {
    // FIPS 180-2, appendix B.1.
    assert_eq!(
        psdcal::sha256_hex(b"abc"),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
}

#[test]
fn psd_maps_and_calibrations_with_them_list_each_input_once_with_its_hash() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (sim, scan, map) = common::simulated_map(d, &[]);
    assert_eq!(inputs(&json(&map)), expected(&[&scan]));

    let template = sim.join("template.csv");
    let observations = sim.join("observations.csv");
    let cal = d.join("cal.json");
    run_ok(&[
        "calibrate",
        "-q",
        "-t",
        s(&template),
        "-o",
        s(&observations),
        "--psd-map",
        s(&map),
        "--out",
        s(&cal),
    ]);
    assert_eq!(
        inputs(&json(&cal)),
        expected(&[&template, &observations, &map])
    );
}
