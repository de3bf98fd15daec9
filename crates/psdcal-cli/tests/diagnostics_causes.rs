//! The diagnostics name the right cause (docs/model.md §4.6–4.7), end to
//! end on simulated data whose cause is known: an unmodelled PSD
//! distortion is named as the term `l1`; a structure no term of the model
//! explains (the PSD's non-radial non-linearity) is not blamed on one; a
//! term already fitted is never suggested; a `--focal-guess` far from the
//! lens is named; the robust loss's scale is in units of the residuals'
//! noise, so that `huber:2.5` flags the corrupted points and only them.

mod common;

use common::{psdcal, stderr};

fn simulate(dir: &std::path::Path, name: &str, extra: &[&str]) -> (String, String) {
    let out = dir.join(name);
    let mut args = vec![
        "-q", "simulate", "--lens", "2", "--snr", "40", "--images", "12", "--seed", "3",
    ];
    args.extend_from_slice(extra);
    let out_text = out.display().to_string();
    args.extend_from_slice(&["--out", &out_text]);
    let run = psdcal(&args);
    assert!(run.status.success(), "{}", stderr(&run));
    (
        out.join("template.csv").display().to_string(),
        out.join("observations.csv").display().to_string(),
    )
}

fn calibrate(t: &str, o: &str, extra: &[&str], out: &std::path::Path) -> std::process::Output {
    let out = out.display().to_string();
    let mut args = vec!["calibrate", "-t", t, "-o", o, "--out", &out];
    args.extend_from_slice(extra);
    psdcal(&args)
}

#[test]
fn the_misfit_names_the_missing_term_and_never_a_fitted_one() {
    let dir = tempfile::tempdir().unwrap();
    let cal = dir.path().join("c.json");
    let (t, o) = simulate(dir.path(), "l1", &["--psd-distortion"]);
    let run = calibrate(&t, &o, &["--fit", "f,cx,cy,k1,k2"], &cal);
    assert!(run.status.success(), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(err.contains("the term l1 explains"), "{err}");
    assert!(err.contains("add l1 to --fit"), "{err}");
    // With l1 fitted the structure is gone, and l1 is never suggested.
    let run = calibrate(&t, &o, &["--fit", "f,cx,cy,k1,k2,l1"], &cal);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(!stderr(&run).contains("model_misfit") && !stderr(&run).contains("l1 to --fit"));
    // Without --fit the data choose l1 themselves.
    let run = calibrate(&t, &o, &[], &cal);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(!stderr(&run).contains("model_misfit"), "{}", stderr(&run));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&cal).unwrap()).unwrap();
    let chosen = &json["fit"]["model_choice"]["chosen"];
    assert!(
        chosen.as_array().unwrap().iter().any(|n| n == "l1"),
        "{chosen}"
    );
    // A non-radial non-linearity: no single term is blamed.
    let (t, o) = simulate(dir.path(), "nl", &["--psd-nonlinearity"]);
    let run = calibrate(&t, &o, &[], &cal);
    let err = stderr(&run);
    assert!(err.contains("that the model cannot follow"), "{err}");
    assert!(!err.contains("to --fit"), "{err}");
    // k1 and k2 are fitted by default: never in the candidates' list.
    assert!(!err.contains("k1 ") && !err.contains("k2 "), "{err}");
}

#[test]
fn a_focal_guess_far_from_the_lens_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (t, o) = simulate(dir.path(), "sim", &[]);
    // Lens 2 has f = 8 mm; the guess's interval is 0.5–2 mm.
    let run = calibrate(&t, &o, &["--focal-guess", "1"], &dir.path().join("c.json"));
    assert_eq!(run.status.code(), Some(1));
    let err = stderr(&run);
    assert!(err.contains("outside the interval searched"), "{err}");
    assert!(err.contains("--focal-guess"), "{err}");
    assert!(!err.contains("parallel"), "{err}");
    // A guess near the lens still works.
    let run = calibrate(&t, &o, &["--focal-guess", "7"], &dir.path().join("c.json"));
    assert!(run.status.success(), "{}", stderr(&run));
}

#[test]
fn the_robust_scale_is_in_units_of_the_noise() {
    let dir = tempfile::tempdir().unwrap();
    let (t, o) = simulate(dir.path(), "sim", &[]);
    // Six of the 168 points moved by 0.3 mm (about 100 σ at 40 dB).
    let text = std::fs::read_to_string(&o).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let header = lines.iter().position(|l| !l.starts_with('#')).unwrap();
    let x = lines[header].split(',').position(|h| h == "x_mm").unwrap();
    for k in [7, 30, 61, 90, 121, 150] {
        let mut fields: Vec<String> = lines[header + 1 + k]
            .split(',')
            .map(str::to_owned)
            .collect();
        fields[x] = (fields[x].parse::<f64>().unwrap() + 0.3).to_string();
        lines[header + 1 + k] = fields.join(",");
    }
    let corrupted = dir.path().join("corrupted.csv");
    std::fs::write(&corrupted, lines.join("\n") + "\n").unwrap();
    let corrupted = corrupted.display().to_string();
    let run = calibrate(
        &t,
        &corrupted,
        &["--robust", "huber:2.5"],
        &dir.path().join("c.json"),
    );
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("6 point(s) down-weighted as outliers"),
        "{}",
        stderr(&run)
    );
    // On the clean data, none: a point is flagged when its weight falls
    // under 1/2, its norm beyond 2 × 2.5 σ (probability e^-12.5 ≈ 4e-6).
    let run = calibrate(
        &t,
        &o,
        &["--robust", "huber:2.5"],
        &dir.path().join("c.json"),
    );
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(!stderr(&run).contains("outliers"), "{}", stderr(&run));
    // A scale under one σ is refused with the units named.
    let run = calibrate(
        &t,
        &o,
        &["--robust", "huber:0.05"],
        &dir.path().join("c.json"),
    );
    assert_eq!(run.status.code(), Some(2));
    assert!(stderr(&run).contains("noise"), "{}", stderr(&run));
}
