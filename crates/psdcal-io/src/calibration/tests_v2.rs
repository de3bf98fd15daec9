//! Tests of calibration.json version 2: the layout, the round trip, the
//! same record as version 1, and the rules that tie stages to parameters.

use nalgebra::Vector3;
use psdcal_model::Pose;

use super::*;

/// A fitted calibration with estimated gains and a provenance, version 2.
fn sample() -> Calibration {
    let mut model = SensorModel::paper_lens2();
    model.distortion.l1 = SensorModel::PAPER_L1;
    let mut cal = Calibration::from_model(&model, &PsdGeometry::default());
    cal.set_estimated(&[Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2]);
    cal.gains = Some(GainsRecord::new(
        &ChannelGains {
            x2: 1.0123,
            y1: 0.9876,
            y2: 1.0 / 3.0,
        },
        true,
    ));
    let names = cal.estimated_names();
    cal.std = StdDevs(
        names
            .iter()
            .enumerate()
            .map(|(k, n)| (n.to_string(), 1e-3 * (k as f64 + 1.0)))
            .collect(),
    );
    let n = names.len();
    cal.covariance = Covariance {
        parameters: names.iter().map(|s| s.to_string()).collect(),
        matrix: (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| {
                        if i == j {
                            1e-6 * (i as f64 + 1.0).powi(2)
                        } else {
                            1e-9
                        }
                    })
                    .collect()
            })
            .collect(),
    };
    cal.images = vec![ImageFit::new(
        "1",
        &Pose::new(Vector3::new(0.1, -0.2, 0.3), Vector3::new(1.0, -2.0, 600.0)),
        0.01,
        14,
    )];
    cal.provenance = Some(Provenance {
        psdcal_version: "0.1.0".into(),
        command: "psdcal calibrate -t t.csv -o o.csv --out c.json".into(),
        options: serde_json::json!({"cost": "template"}),
        inputs: vec![InputFile {
            path: "t.csv".into(),
            sha256: "00".repeat(32),
        }],
        created_utc: "2024-01-02T03:04:05Z".into(),
    });
    cal
}

fn json(cal: &Calibration) -> serde_json::Value {
    serde_json::from_str(&cal.to_json_string("c.json").unwrap()).unwrap()
}

#[test]
fn new_records_are_version_2_with_stages_and_flat_parameters() {
    let v = json(&sample());
    assert_eq!(v["version"], 2);
    assert_eq!(v["parameters"]["f"], 8.0);
    assert_eq!(v["parameters"]["l1"], -1.3058e-3);
    assert_eq!(v["parameters"]["g_x2"], 1.0123);
    let kinds: Vec<&str> = v["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["gains", "psd_radial", "lens", "pinhole"]);
    assert_eq!(v["stages"][2]["parameters"]["k2"], 3e-5);
    assert_eq!(
        v["stages"][2]["estimated"],
        serde_json::json!(["cx", "cy", "k1", "k2"])
    );
    assert_eq!(v["stages"][3]["estimated"], serde_json::json!(["f"]));
    assert_eq!(
        v["stages"][0]["estimated"],
        serde_json::json!(["g_x2", "g_y1", "g_y2"])
    );
    assert_eq!(v["covariance"]["parameters"][5], "g_x2");
    assert_eq!(v["diagnostics"], serde_json::json!([]));
    assert_eq!(v["provenance"]["inputs"][0]["path"], "t.csv");
    assert!(v.get("intrinsics").is_none());
    let plain = json(&Calibration::from_model(
        &SensorModel::paper_lens1(),
        &PsdGeometry::default(),
    ));
    assert_eq!(plain["stages"].as_array().unwrap().len(), 3);
    assert!(plain["parameters"].get("g_x2").is_none());
}

#[test]
fn version_2_round_trip_is_exact_and_equals_version_1() {
    let cal = sample();
    let text = cal.to_json_string("c.json").unwrap();
    let back = Calibration::from_json_str("c.json", &text).unwrap();
    assert_eq!(back, cal);
    let mut v1 = cal.clone();
    v1.version = 1;
    let from_v1 =
        Calibration::from_json_str("c.json", &v1.to_json_string("c.json").unwrap()).unwrap();
    assert_eq!(from_v1.to_model(), back.to_model());
    assert_eq!(from_v1.gains(), back.gains());
    assert_eq!(from_v1.std, back.std);
    assert_eq!(from_v1.covariance, back.covariance);
    assert_eq!(from_v1.estimated, back.estimated);
}

#[test]
fn stages_and_parameters_must_agree() {
    let v = json(&sample());
    let read = |v: &serde_json::Value| {
        Calibration::from_json_str("c.json", &serde_json::to_string_pretty(v).unwrap())
            .unwrap_err()
            .to_string()
    };
    let mut bad = v.clone();
    bad["parameters"]["f"] = serde_json::json!(9.0);
    assert!(
        read(&bad).contains("parameters.f is 9 but its stage says 8"),
        "{}",
        read(&bad)
    );
    let mut bad = v.clone();
    bad["stages"][2]["parameters"]["zoom"] = serde_json::json!(1.0);
    assert!(read(&bad).contains("'zoom' is not a parameter of a 'lens' stage"));
    let mut bad = v.clone();
    bad["stages"][3]["kind"] = serde_json::json!("fisheye");
    assert!(read(&bad).contains("unknown variant `fisheye`"));
    let mut bad = v.clone();
    bad["stages"].as_array_mut().unwrap().remove(3);
    assert!(read(&bad).contains("no 'pinhole' stage"));
    let mut bad = v.clone();
    bad["stages"][0]["estimated"] = serde_json::json!(["g_x2"]);
    assert!(read(&bad).contains("estimated together"));
}

/// A lens folding at r* = 1/√(3 · 0.02) = 4.08 mm about (0.5, −0.7).
fn folding() -> Calibration {
    let mut model = SensorModel::pinhole(8.0, 0.5, -0.7);
    model.distortion.k1 = -0.02;
    Calibration::from_model(&model, &PsdGeometry::default())
}

#[test]
fn the_valid_region_is_written_when_stored_and_read_back_exactly() {
    let mut cal = folding();
    assert!(json(&cal).get("valid_region").is_none());
    cal.store_valid_region();
    let v = json(&cal);
    let region = &v["valid_region"];
    assert_eq!(region["centre_mm"], serde_json::json!([0.5, -0.7]));
    assert_eq!(region["rays"], 90);
    assert_eq!(region["whole_active_area"], false);
    let r_star = 1.0 / (3.0f64 * 0.02).sqrt();
    let radii = region["radius_mm"].as_array().unwrap();
    assert_eq!(radii.len(), 90);
    assert!(radii
        .iter()
        .all(|r| (r.as_f64().unwrap() - r_star).abs() < 1e-9));
    let back =
        Calibration::from_json_str("c.json", &cal.to_json_string("c.json").unwrap()).unwrap();
    assert_eq!(back, cal);
    assert_eq!(back.valid_region(), cal.valid_region());
    // Without a stored region (version 1, older version 2 files) the same
    // region is computed from the model.
    let mut bare = cal.clone();
    bare.valid_region = None;
    assert_eq!(bare.valid_region(), cal.valid_region());
    let mut v1 = cal.clone();
    v1.version = 1;
    let text = v1.to_json_string("c.json").unwrap();
    assert!(!text.contains("valid_region"));
    let from_v1 = Calibration::from_json_str("c.json", &text).unwrap();
    assert_eq!(from_v1.valid_region, None);
    assert_eq!(from_v1.valid_region(), cal.valid_region());
}

#[test]
fn a_valid_region_that_contradicts_itself_is_refused() {
    let mut cal = folding();
    cal.store_valid_region();
    let v = json(&cal);
    let read = |v: &serde_json::Value| {
        Calibration::from_json_str("c.json", &serde_json::to_string_pretty(v).unwrap())
            .unwrap_err()
            .to_string()
    };
    let mut bad = v.clone();
    bad["valid_region"]["whole_active_area"] = serde_json::json!(true);
    assert!(read(&bad).contains("valid_region.whole_active_area is true but its radii say false"));
    let mut bad = v.clone();
    bad["valid_region"]["rays"] = serde_json::json!(12);
    assert!(read(&bad).contains("valid_region.rays is 12 but valid_region.radius_mm has 90"));
    let mut bad = v.clone();
    bad["valid_region"]["radius_mm"][7] = serde_json::json!(-1.0);
    assert!(
        read(&bad).contains("radius -1 mm of ray 7"),
        "{}",
        read(&bad)
    );
    let mut bad = v.clone();
    bad["valid_region"]["radius_mm"] = serde_json::json!([1.0, 1.0]);
    bad["valid_region"]["rays"] = serde_json::json!(2);
    assert!(read(&bad).contains("expected at least 8"), "{}", read(&bad));
}

#[test]
fn diagnostics_round_trip_with_their_stable_codes() {
    use psdcal_model::{Diagnostic, DiagnosticCode};
    let mut cal = sample();
    cal.diagnostics = vec![
        Diagnostic::warning(DiagnosticCode::GainImbalanceSuspected, "fit the gains"),
        Diagnostic::info(DiagnosticCode::LocalMinimumSuspected, "found once"),
    ];
    let v = json(&cal);
    assert_eq!(
        v["diagnostics"],
        serde_json::json!([
            {"code": "gain_imbalance_suspected", "severity": "warning", "message": "fit the gains"},
            {"code": "local_minimum_suspected", "severity": "info", "message": "found once"}
        ])
    );
    let text = cal.to_json_string("c.json").unwrap();
    let back = Calibration::from_json_str("c.json", &text).unwrap();
    assert_eq!(back.diagnostics, cal.diagnostics);
    // An unknown code is refused with the file's name.
    let bad = text.replace("gain_imbalance_suspected", "gain_trouble");
    let err = Calibration::from_json_str("c.json", &bad).unwrap_err();
    assert!(err.to_string().contains("c.json"), "{err}");
}

/// `sample()` with a polynomial PSD map of order 1 (3 coefficients per
/// axis), held fixed or refined (`matrix`, all names `estimated`).
fn with_map(refined: bool) -> Calibration {
    use psdcal_model::stages::{MapBasis, MapFrame, PsdMap};
    use psdcal_model::Stage;
    let stage = PsdMap::new(
        MapBasis::Polynomial { order: 1 },
        MapFrame::centred(9.0, 9.0),
        None,
    )
    .unwrap();
    let mut cal = sample();
    let k = stage.terms();
    let nt = cal.covariance.parameters.len();
    let matrix = (0..2 * k)
        .map(|i| {
            (0..2 * k)
                .map(|j| if i == j { 4e-6 } else { 1e-7 })
                .collect()
        })
        .collect();
    cal.psd_map = Some(PsdMapStageRecord {
        configuration: stage.configuration(),
        parameters: stage
            .parameters()
            .iter()
            .enumerate()
            .map(|(i, p)| (p.name.clone(), 1e-3 * i as f64))
            .collect(),
        covariance: PsdMapStageCovariance {
            sigma_x_mm: 3e-4,
            sigma_y_mm: 4e-4,
            unit: (0..k)
                .map(|i| (0..k).map(|j| if i == j { 2.0 } else { 0.1 }).collect())
                .collect(),
            cross: vec![vec![1e-8; nt]; 2 * k],
            matrix: refined.then_some(matrix),
        },
        estimated: refined,
        scan: None,
    });
    cal
}

#[test]
fn a_psd_map_stage_round_trips_held_or_refined() {
    for refined in [false, true] {
        let cal = with_map(refined);
        let text = cal.to_json_string("c.json").unwrap();
        let back = Calibration::from_json_str("c.json", &text).unwrap();
        assert_eq!(back, cal);
        let map = back.psd_map.as_ref().unwrap();
        let (stage, _) = map.to_stage(cal.covariance.parameters.len()).unwrap();
        let c = map.map_covariance(&stage).unwrap();
        // Held: σx² U on the x block (2 · 9e-8); refined: the matrix (4e-6).
        let expected = if refined { 4e-6 } else { 2.0 * 9e-8 };
        assert!((c.matrix()[(0, 0)] - expected).abs() < 1e-18, "{refined}");
        let stages = &json(&cal)["stages"];
        let map_json = stages
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["kind"] == "psd_map")
            .unwrap();
        assert_eq!(
            map_json["estimated"].as_array().unwrap().len(),
            if refined { 6 } else { 0 }
        );
        assert_eq!(map_json["covariance"].get("matrix").is_some(), refined);
    }
}

/// The byte range of the array value of `"key"`, the first after the
/// psd_map stage's kind in `text` (brackets matched).
fn array_in_map_stage(text: &str, key: &str) -> std::ops::Range<usize> {
    let stage = text.find("\"kind\": \"psd_map\"").unwrap();
    let start = stage + text[stage..].find(&format!("\"{key}\": [")).unwrap() + key.len() + 4;
    let mut depth = 0;
    for (i, c) in text[start..].char_indices() {
        match c {
            '[' => depth += 1,
            ']' => {
                depth -= 1;
                if depth == 0 {
                    return start..start + i + 1;
                }
            }
            _ => {}
        }
    }
    panic!("unbalanced {key}")
}

#[test]
fn a_refined_psd_map_needs_all_its_names_and_its_matrix() {
    let read = |text: &str| {
        Calibration::from_json_str("c.json", text)
            .unwrap_err()
            .to_string()
    };
    let text = with_map(true).to_json_string("c.json").unwrap();
    let mut bad = text.clone();
    bad.replace_range(array_in_map_stage(&text, "estimated"), "[\"map_x_0_0\"]");
    assert!(
        read(&bad).contains("none of its parameters"),
        "{}",
        read(&bad)
    );
    // Held (nothing estimated) with a matrix.
    let mut bad = text.clone();
    bad.replace_range(array_in_map_stage(&text, "estimated"), "[]");
    assert!(read(&bad).contains("carries 'matrix'"), "{}", read(&bad));
    let mut bad = text.clone();
    bad.replace_range(array_in_map_stage(&text, "matrix"), "[[1.0]]");
    assert!(
        read(&bad).contains("'matrix' must be 6 × 6"),
        "{}",
        read(&bad)
    );
    // Refined without its matrix.
    let range = array_in_map_stage(&text, "matrix");
    let key = text[..range.start].rfind(",").unwrap();
    let mut bad = text.clone();
    bad.replace_range(key..range.end, "");
    assert!(read(&bad).contains("carries 'matrix'"), "{}", read(&bad));
}

/// `value` as JSON text with every object's keys in reverse alphabetical
/// order (what no writer of psdcal produces).
fn reordered(value: &serde_json::Value) -> String {
    match value {
        serde_json::Value::Object(map) => {
            let mut keys: Vec<&String> = map.keys().collect();
            keys.sort_unstable_by(|a, b| b.cmp(a));
            let fields: Vec<String> = keys
                .into_iter()
                .map(|k| {
                    format!(
                        "{}:{}",
                        serde_json::Value::from(k.as_str()),
                        reordered(&map[k])
                    )
                })
                .collect();
            format!("{{{}}}", fields.join(","))
        }
        serde_json::Value::Array(items) => {
            let items: Vec<String> = items.iter().map(reordered).collect();
            format!("[{}]", items.join(","))
        }
        other => other.to_string(),
    }
}

/// A scan summary for [`with_map`]'s stage: two cells.
fn scan_summary() -> crate::PsdMapScanRecord {
    crate::PsdMapScanRecord {
        model: "poly:1".into(),
        fit: crate::MapFitRecord {
            points: 9,
            from_amplitudes: false,
            rejected_lines: vec![4],
            folds: 5,
            cv_rms_um: 0.41,
            rms_um: 0.38,
            sigma_x_um: 0.3,
            sigma_y_um: 0.4,
            map_sigma_um: 0.1,
            effective_terms: 3.0,
            candidates: vec![crate::MapCandidateRecord {
                model: "poly:1".into(),
                cv_rms_um: 0.41,
            }],
        },
        residual_cells: crate::ScanResidualCells {
            cells: 2,
            x_mm: vec![-2.25, 2.25],
            y_mm: vec![-2.25, 2.25],
            points: vec![5, 3],
            dx_um: vec![0.1, -0.2],
            dy_um: vec![0.0, 0.05],
            rms_um: vec![0.4, 0.35],
        },
    }
}

#[test]
fn key_order_carries_no_meaning() {
    // A tool that sorts or shuffles an object's keys (jq -S, Python's
    // sort_keys) leaves the same calibration: std follows the covariance's
    // parameter list, not its own key order.
    let cal = sample();
    let text = reordered(&json(&cal));
    assert!(text.find("\"std\"").is_some());
    let std_at = text.find("\"std\":{").unwrap();
    assert!(
        text[std_at..].find("\"k2\"").unwrap() < text[std_at..].find("\"cx\"").unwrap(),
        "the test's std must be out of the covariance's order"
    );
    let read = Calibration::from_json_str("sorted.json", &text).expect("reads");
    assert_eq!(read, cal);
}

#[test]
fn a_psd_map_stage_carries_its_scan_summary_and_files_without_it_still_read() {
    let mut cal = with_map(false);
    let without = cal.to_json_string("c.json").unwrap();
    assert!(!without.contains("\"scan\""));
    cal.psd_map.as_mut().unwrap().scan = Some(scan_summary());
    let text = cal.to_json_string("c.json").unwrap();
    let back = Calibration::from_json_str("c.json", &text).unwrap();
    assert_eq!(back, cal);
    let stage = json(&cal)["stages"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["kind"] == "psd_map")
        .unwrap()
        .clone();
    assert_eq!(stage["scan"]["fit"]["cv_rms_um"], 0.41);
    assert_eq!(stage["scan"]["residual_cells"]["points"][1], 3);
    // A file without it (older psdcal) reads, with no summary.
    let old = Calibration::from_json_str("c.json", &without).unwrap();
    assert!(old.psd_map.unwrap().scan.is_none());
    // A column of another length, or a summary on another stage: refused.
    let mut bad = cal.clone();
    let scan = bad.psd_map.as_mut().unwrap().scan.as_mut().unwrap();
    scan.residual_cells.rms_um.pop();
    let err = Calibration::from_json_str("c.json", &bad.to_json_string("c.json").unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("c.json") && err.contains("residual_cells"),
        "{err}"
    );
    let mut value = json(&cal);
    let stages = value["stages"].as_array_mut().unwrap();
    let lens = stages.iter().position(|s| s["kind"] == "lens").unwrap();
    stages[lens]["scan"] = stage["scan"].clone();
    let misplaced = serde_json::to_string(&value).unwrap();
    let err = Calibration::from_json_str("c.json", &misplaced)
        .unwrap_err()
        .to_string();
    assert!(err.contains("'scan' belongs to a psd_map stage"), "{err}");
}
