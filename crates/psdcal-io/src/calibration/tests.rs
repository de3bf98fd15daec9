//! Tests of calibration.json: round trip, named fields, and every rule with
//! the line its error names.

use nalgebra::Vector3;
use psdcal_model::Pose;

use super::*;

/// A fully populated calibration, as a fit would write it.
fn sample() -> Calibration {
    let mut model = SensorModel::paper_lens2();
    model.intrinsics.f = 8.000123456789;
    model.distortion.l1 = SensorModel::PAPER_L1;
    let mut cal = Calibration::from_model(&model, &PsdGeometry::default());
    // These tests are of the version 1 layout (version 2: tests_v2.rs).
    cal.version = 1;
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
                            1e-9 * (i + j) as f64 + 0.1 / 7.0 * 1e-9
                        }
                    })
                    .collect()
            })
            .collect(),
    };
    cal.fit = FitSummary {
        cost: CostKind::Image,
        noise: "channel-snr".into(),
        residual_mm2: 1.234e-2,
        rms_template_mm: 0.0123,
        rms_image_mm: 4.5e-4,
        iterations: 17,
        points: 42,
        images: 3,
        termination: "relative cost change below 1e-12".into(),
        uncertainty: "bootstrap".into(),
        bootstrap: Some(BootstrapRecord {
            resamples: 50,
            failed: 1,
            seed: 9,
        }),
        model_choice: None,
    };
    cal.images = vec![
        ImageFit::new(
            "1",
            &Pose::new(Vector3::new(0.1, -0.2, 0.3), Vector3::new(1.0, -2.0, 600.0)),
            0.01,
            14,
        ),
        ImageFit::new("im 2", &Pose::identity(), 0.0, 12),
    ];
    cal
}

#[test]
fn write_read_round_trip_is_exact() {
    let cal = sample();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("calibration.json");
    write_calibration(&path, &cal).unwrap();
    let back = read_calibration(&path).unwrap();
    assert_eq!(back, cal);
    assert_eq!(back.to_model(), cal.to_model());
    assert_eq!(back.to_model().intrinsics.f, 8.000123456789);
    let minimal = Calibration::from_model(&SensorModel::paper_lens1(), &PsdGeometry::default());
    write_calibration(&path, &minimal).unwrap();
    assert_eq!(read_calibration(&path).unwrap(), minimal);
}

#[test]
fn json_has_named_fields() {
    let text = sample().to_json_string("c.json").unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["format"], "psdcal-calibration");
    assert_eq!(v["version"], 1);
    assert_eq!(v["software"]["name"], "psdcal");
    assert_eq!(v["software"]["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(v["sensor"]["lx_mm"], 9.0);
    assert_eq!(v["intrinsics"]["f_mm"], 8.000123456789);
    assert_eq!(v["intrinsics"]["cy_mm"], -0.7);
    assert_eq!(v["distortion"]["k2"], 3e-5);
    assert_eq!(v["distortion"]["l1"], -1.3058e-3);
    assert_eq!(
        v["estimated"],
        serde_json::json!(["f", "cx", "cy", "k1", "k2"])
    );
    assert_eq!(
        v["fixed"],
        serde_json::json!(["skew", "k3", "p1", "p2", "l1", "l2"])
    );
    assert_eq!(v["gains"]["x1"], 1.0);
    assert_eq!(v["gains"]["estimated"], true);
    let std_keys: Vec<&String> = v["std"].as_object().unwrap().keys().collect();
    assert_eq!(std_keys.len(), 8);
    assert_eq!(v["std"]["g_y2"], 8e-3);
    assert_eq!(v["covariance"]["parameters"][5], "g_x2");
    assert_eq!(v["fit"]["cost"], "image");
    assert_eq!(
        v["images"][0]["t_mm"],
        serde_json::json!([1.0, -2.0, 600.0])
    );
    let minimal = Calibration::from_model(&SensorModel::paper_lens1(), &PsdGeometry::default())
        .to_json_string("c.json")
        .unwrap();
    let v: serde_json::Value = serde_json::from_str(&minimal).unwrap();
    assert!(v["gains"].is_null());
}

#[test]
fn accessors() {
    let cal = sample();
    assert_eq!(cal.geometry(), PsdGeometry { lx: 9.0, ly: 9.0 });
    let g = cal.gains().unwrap();
    assert_eq!((g.x2, g.y1, g.y2), (1.0123, 0.9876, 1.0 / 3.0));
    assert_eq!(cal.std.get("cx"), Some(2e-3));
    assert_eq!(cal.covariance.get("f", "f"), Some(1e-6));
    assert_eq!(cal.images[0].pose().t, Vector3::new(1.0, -2.0, 600.0));
    let mut absolute = cal.gains.unwrap();
    absolute.x1 = 2.0;
    absolute.x2 = 4.0;
    assert_eq!(absolute.to_gains().x2, 2.0);
}

fn json(cal: &Calibration) -> String {
    cal.to_json_string("c.json").unwrap()
}

fn read(text: &str) -> IoError {
    Calibration::from_json_str("calibration.json", text).unwrap_err()
}

/// The 1-based line of the first occurrence of `needle` in `text`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn wrong_format_name_is_reported_on_its_line() {
    let text = json(&sample()).replace("\"psdcal-calibration\"", "\"other-tool\"");
    let e = read(&text);
    assert_eq!(e.line(), Some(2));
    assert_eq!(
        e.to_string(),
        "calibration.json:2:24: \"format\" is \"other-tool\"; expected \
         \"psdcal-calibration\" (this is not a psdcal calibration file)"
    );
}

#[test]
fn newer_version_is_refused_older_accepted() {
    let text = json(&sample());
    // A version 3 file whose intrinsics changed shape: the version wins.
    let newer = text
        .replace("\"version\": 1,", "\"version\": 3,")
        .replace("\"f_mm\"", "\"fx_mm\"");
    let e = read(&newer);
    assert!(matches!(
        e,
        IoError::NewerVersion {
            found: 3,
            supported: 2,
            ..
        }
    ));
    assert_eq!(
        e.to_string(),
        "calibration.json:3:14: format version 3 was written by a newer psdcal; this psdcal \
         reads versions up to 2"
    );
    let older = text.replace("\"version\": 1,", "\"version\": 0,");
    assert_eq!(
        Calibration::from_json_str("c.json", &older)
            .unwrap()
            .version,
        0
    );
}

#[test]
fn unknown_fields_are_ignored() {
    let text = json(&sample()).replacen(
        "{",
        "{\n  \"added_in_v2\": {\"x\": [1, 2]},\n  \"note\": \"hi\",",
        1,
    );
    assert_eq!(
        Calibration::from_json_str("c.json", &text).unwrap(),
        sample()
    );
}

#[test]
fn non_positive_focal_length_is_reported_on_its_line() {
    let text = json(&sample()).replace("\"f_mm\": 8.000123456789", "\"f_mm\": -1.0");
    let e = read(&text);
    let line = line_of(&text, "\"f_mm\"");
    assert_eq!(e.line(), Some(line));
    assert_eq!(
        e.to_string(),
        format!("calibration.json:{line}:16: expected a positive number of mm, found -1")
    );
}

#[test]
fn json_syntax_errors_have_line_and_column() {
    let text = json(&sample());
    let cut = &text[..text.len() / 2];
    let e = read(cut);
    assert_eq!(e.line(), Some(cut.lines().count()));
    assert!(e
        .to_string()
        .starts_with(&format!("calibration.json:{}:", cut.lines().count())));
    assert!(e.to_string().contains("EOF while parsing"), "{e}");
    let e = read("");
    assert_eq!(e.line(), Some(1));
    let e = read(&text.replace("\"iterations\": 17", "\"iterations\": -3"));
    assert_eq!(e.line(), Some(line_of(&text, "\"iterations\"")));
    let e = read(&text.replace("8.000123456789", "1e400"));
    assert!(e.to_string().contains("number out of range"), "{e}");
    let e = Calibration::from_json_bytes("c.json", b"{\n\"format\": \"\xff\"}").unwrap_err();
    assert_eq!(e.line(), Some(2));
}

#[test]
fn unknown_parameter_names_are_rejected_on_their_line() {
    let text = json(&sample()).replacen("\"cx\",", "\"fx\",", 1);
    let e = read(&text);
    assert_eq!(e.line(), Some(line_of(&text, "\"fx\"")));
    assert!(e.to_string().contains("unknown variant `fx`"), "{e}");
}

#[test]
fn covariance_must_be_square_and_symmetric() {
    let mut cal = sample();
    cal.covariance.matrix[1][0] = 0.5;
    cal.covariance.matrix[0][1] = 0.25;
    let e = cal.validate("c.json").unwrap_err();
    assert_eq!(
        e.to_string(),
        "c.json: covariance.matrix is not symmetric: [1][0] = 0.5 but [0][1] = 0.25"
    );
    // Rounding-level asymmetry is accepted.
    let mut cal = sample();
    cal.covariance.matrix[1][0] *= 1.0 + 1e-12;
    assert!(cal.validate("c.json").is_ok());
    let text = json(&sample());
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut v2 = v.clone();
    v2["covariance"]["matrix"][1][0] = serde_json::json!(5.0);
    let bad = serde_json::to_string_pretty(&v2).unwrap();
    let e = read(&bad);
    assert!(matches!(e, IoError::Json { .. }));
    assert!(e.to_string().contains("is not symmetric"), "{e}");
    let mut cal = sample();
    cal.covariance.matrix.pop();
    let e = cal.validate("c.json").unwrap_err();
    assert!(e.to_string().contains("has 7 rows for 8 parameters"), "{e}");
}

#[test]
fn cross_field_rules() {
    let mut cal = sample();
    cal.fixed.push(Param::F);
    assert_eq!(
        cal.validate("c.json").unwrap_err().to_string(),
        "c.json: 'f' is both estimated and fixed; expected each parameter in one list"
    );
    let mut cal = sample();
    cal.estimated.push(Param::Cx);
    assert_eq!(
        cal.validate("c.json").unwrap_err().to_string(),
        "c.json: 'estimated' lists 'cx' twice; expected each once"
    );
    let mut cal = sample();
    cal.std.0.remove(0);
    assert_eq!(
        cal.validate("c.json").unwrap_err().to_string(),
        "c.json: 'std' has entries [cx, cy, k1, k2, g_x2, g_y1, g_y2]; expected one per \
         estimated parameter: [f, cx, cy, k1, k2, g_x2, g_y1, g_y2]"
    );
    let mut cal = sample();
    cal.covariance.parameters.swap(0, 1);
    assert!(cal
        .validate("c.json")
        .unwrap_err()
        .to_string()
        .contains("must list the names of 'std' in the same order"));
    let mut cal = sample();
    cal.images[1].id = "1".into();
    assert!(cal
        .validate("c.json")
        .unwrap_err()
        .to_string()
        .contains("image id '1' appears twice"));
}

#[test]
fn writing_refuses_non_finite_values_and_leaves_no_file() {
    let mut cal = sample();
    cal.distortion.k2 = f64::NAN;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.json");
    let e = write_calibration(&path, &cal).unwrap_err();
    assert!(e
        .to_string()
        .ends_with("distortion.k2 must be a finite number"));
    assert!(!path.exists());
    let mut cal = sample();
    cal.intrinsics.f_mm = 0.0;
    assert!(cal
        .validate("c.json")
        .unwrap_err()
        .to_string()
        .ends_with("intrinsics.f_mm must be a positive number, found 0"));
    let mut cal = sample();
    cal.fit.rms_image_mm = f64::INFINITY;
    assert!(cal
        .validate("c.json")
        .unwrap_err()
        .to_string()
        .ends_with("fit.rms_image_mm must be zero or a positive number, found a non-finite value"));
}

#[test]
fn gains_and_std_are_checked_when_read() {
    let text = json(&sample());
    let e = read(&text.replace("\"y1\": 0.9876", "\"y1\": 0.0"));
    assert!(
        e.to_string()
            .contains("gains.y1 must be a positive number, found 0"),
        "{e}"
    );
    assert!(matches!(e, IoError::Json { .. }));
    let e = read(&text.replace("\"cx\": 0.002", "\"cx\": -0.002"));
    assert_eq!(e.line(), Some(line_of(&text, "\"cx\": 0.002")));
    assert!(
        e.to_string().contains("std.cx must be zero or positive"),
        "{e}"
    );
}

#[test]
fn bom_and_crlf_are_accepted() {
    let text = format!("\u{feff}{}", json(&sample()).replace('\n', "\r\n"));
    assert_eq!(
        Calibration::from_json_bytes("c.json", text.as_bytes()).unwrap(),
        sample()
    );
    // Lines are still counted right.
    let bad = text.replace("\"f_mm\": 8.000123456789", "\"f_mm\": 0");
    let e = Calibration::from_json_str("c.json", &bad).unwrap_err();
    assert_eq!(e.line(), Some(line_of(&json(&sample()), "\"f_mm\"")));
}

#[test]
fn integer_image_ids_are_read_as_text() {
    let text = json(&sample()).replace("\"id\": \"1\"", "\"id\": 1");
    let cal = Calibration::from_json_str("c.json", &text).unwrap();
    assert_eq!(cal.images[0].id, "1");
}

#[test]
fn files_written_before_the_noise_model_read_as_uniform() {
    let text = json(&sample());
    let before = text.replace("    \"noise\": \"channel-snr\",\n", "");
    assert_ne!(before, text, "the sample writes its noise model");
    let read = Calibration::from_json_str("c.json", &before).unwrap();
    assert_eq!(read.fit.noise, "uniform");
    assert_eq!(
        Calibration::from_json_str("c.json", &text)
            .unwrap()
            .fit
            .noise,
        "channel-snr"
    );
}

#[test]
fn physically_impossible_values_are_refused() {
    // f = 1e-300 mm: below 10 µm.
    let mut cal = sample();
    cal.intrinsics.f_mm = 1e-300;
    let e = cal.validate("c.json").unwrap_err().to_string();
    assert!(
        e.starts_with("c.json: intrinsics.f_mm is 1e-300, below"),
        "{e}"
    );
    // |skew| ≥ f (1e300 answered alpha −90° and a zero ray).
    for skew in [1e300, -8.5] {
        let mut cal = sample();
        cal.intrinsics.skew = skew;
        let e = cal.validate("c.json").unwrap_err().to_string();
        assert!(e.starts_with("c.json: |intrinsics.skew| is"), "{e}");
    }
    let mut cal = sample();
    cal.intrinsics.skew = 0.01;
    cal.validate("c.json").unwrap();
}

#[test]
fn std_must_be_the_root_of_the_covariance_diagonal() {
    // σ × 1e150 in `std` alone: the printed and the propagated σ disagree.
    let mut cal = sample();
    cal.std.0[0].1 *= 1e150;
    let e = cal.validate("c.json").unwrap_err().to_string();
    assert!(
        e.starts_with("c.json: std.f is 1e147 but the square root"),
        "{e}"
    );
    // Rounding of a written file is within the tolerance.
    let mut cal = sample();
    cal.std.0[0].1 *= 1.0 + 1e-9;
    cal.validate("c.json").unwrap();
}

#[test]
fn covariance_must_be_positive_semidefinite() {
    // A correlation of 10 between f and cx: eigenvalue 1 − 10 of the 2×2
    // block, whatever the scales.
    let mut cal = sample();
    let c = &mut cal.covariance.matrix;
    let r = 10.0 * (c[0][0] * c[1][1]).sqrt();
    c[0][1] = r;
    c[1][0] = r;
    let e = cal.validate("c.json").unwrap_err().to_string();
    assert!(
        e.contains("covariance.matrix is not positive semi-definite"),
        "{e}"
    );
    // A zero variance with a non-zero covariance cannot be a covariance.
    let mut cal = sample();
    cal.covariance.matrix[0][0] = 0.0;
    cal.std.0[0].1 = 0.0;
    let e = cal.validate("c.json").unwrap_err().to_string();
    assert!(e.contains("but 'f' has variance 0"), "{e}");
    // A perfect correlation (rank-deficient, still a covariance) passes.
    let mut cal = sample();
    let c = &mut cal.covariance.matrix;
    let r = (c[0][0] * c[1][1]).sqrt();
    for (i, row) in c.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            if i != j {
                *v = 0.0;
            }
        }
    }
    c[0][1] = r;
    c[1][0] = r;
    cal.validate("c.json").unwrap();
}
