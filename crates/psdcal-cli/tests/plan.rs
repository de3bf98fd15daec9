//! `psdcal plan` → `simulate --poses` → `calibrate` → `plan --next` and
//! `focal-check`, end to end, with the refusals.

mod common;

use common::{psdcal, stderr, stdout};
use nalgebra::Vector2;
use psdcal_model::SensorModel;

fn json(output: &std::process::Output) -> serde_json::Value {
    assert!(output.status.success(), "{}", stderr(output));
    serde_json::from_str(&stdout(output)).expect("JSON on stdout")
}

/// `psdcal plan --json` for lens 2's nominal model (f = 8 mm, the paper's
/// k1, k2 and centre), 9 poses of `template` at 40 dB with a 0.3 mm
/// margin, then `extra`.
fn plan_lens2(template: &str, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "plan",
        "--json",
        "--f",
        "8",
        "--set",
        "k1=1e-2",
        "--set",
        "k2=3e-5",
        "--set",
        "cx=0.5",
        "--set",
        "cy=-0.7",
        "--margin",
        "0.3",
        "--template",
        template,
        "--snr",
        "40",
        "--images",
        "9",
    ];
    args.extend_from_slice(extra);
    json(&psdcal(args))
}

#[test]
fn plan_simulate_calibrate_next_and_focal_check() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name).display().to_string();
    assert!(
        psdcal(["simulate", "--snr", "40", "-q", "--out", &d("sim")])
            .status
            .success()
    );
    let template = d("sim/template.csv");
    let planned = plan_lens2(
        &template,
        &["--out", &d("poses.csv"), "--report", &d("rep")],
    );
    assert_eq!(planned["poses"].as_array().unwrap().len(), 9);
    let rms = planned["aoa_sigma_deg"]["rms"].as_f64().unwrap();
    assert!(rms > 0.0 && rms <= planned["aoa_sigma_deg"]["max"].as_f64().unwrap());
    assert!(dir.path().join("rep/plan_sigma.svg").exists());
    // The planned poses simulate (every LED on the area) and calibrate.
    let sim = json(&psdcal([
        "simulate",
        "--json",
        "--snr",
        "40",
        "--poses",
        &d("poses.csv"),
        "--out",
        &d("sim2"),
    ]));
    assert_eq!(sim["images"], 9);
    assert!(psdcal([
        "calibrate",
        "-q",
        "--template",
        &d("sim2/template.csv"),
        "--observations",
        &d("sim2/observations.csv"),
        "--out",
        &d("cal.json"),
    ])
    .status
    .success());
    let next = json(&psdcal([
        "plan",
        "--json",
        "--next",
        "--calibration",
        &d("cal.json"),
        "--template",
        &template,
        "--snr",
        "40",
        "--out",
        &d("next.csv"),
    ]));
    assert_eq!(next["poses"].as_array().unwrap().len(), 1);
    let before = next["before_aoa_sigma_deg"]["rms"].as_f64().unwrap();
    assert!(next["aoa_sigma_deg"]["rms"].as_f64().unwrap() < before);

    // A 300 mm square at 350 mm imaged through the true lens 2: the check
    // recovers the true f (8 mm) within the calibration's error.
    let truth = SensorModel::paper_lens2();
    let (s, half) = (350.0, 150.0);
    let mut corners = String::from("corner,x_mm,y_mm,sigma_mm\n");
    for (k, (x, y)) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .enumerate()
    {
        let ideal = Vector2::new(
            truth.intrinsics.cx + truth.intrinsics.f * x * half / s,
            truth.intrinsics.cy + truth.intrinsics.f * y * half / s,
        );
        let m = psdcal_model::Model::standard(&truth)
            .measured_from_ideal_to_tolerance(&ideal)
            .unwrap();
        corners += &format!("c{},{},{},0.0005\n", k + 1, m.x, m.y);
    }
    std::fs::write(dir.path().join("corners.csv"), corners).unwrap();
    let check = json(&psdcal([
        "focal-check",
        "--json",
        "--calibration",
        &d("cal.json"),
        "--points",
        &d("corners.csv"),
        "--distance",
        "350",
        "--size",
        "300",
    ]));
    let f = check["f_check_mm"].as_f64().unwrap();
    let sigma = check["sigma_check_mm"].as_f64().unwrap();
    let sigma_cal = check["sigma_f_calibration_mm"].as_f64().unwrap();
    assert!(sigma > 0.0 && sigma_cal > 0.0);
    assert!(
        (f - 8.0).abs() < 5.0 * (sigma + sigma_cal) + 0.02,
        "f check {f}"
    );
    // Each side by hand: |Δideal| · S / side, from the calibration's own f.
    assert_eq!(check["f_sides_mm"].as_array().unwrap().len(), 4);

    // Refusals with what to change.
    let three = "corner,x_mm,y_mm\na,0,0\nb,1,0\nc,1,1\n";
    std::fs::write(dir.path().join("three.csv"), three).unwrap();
    let out = psdcal([
        "focal-check",
        "--calibration",
        &d("cal.json"),
        "--points",
        &d("three.csv"),
        "--distance",
        "350",
        "--size",
        "300",
    ]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("four corners"), "{}", stderr(&out));
    let out = psdcal([
        "plan",
        "--f",
        "8",
        "--template",
        &template,
        "--snr",
        "40",
        "--distance",
        "10:20",
        "--out",
        &d("p.csv"),
    ]);
    assert!(!out.status.success() && stderr(&out).contains("allow distances up to"));
    let out = psdcal([
        "plan",
        "--f",
        "8",
        "--template",
        &template,
        "--snr",
        "40",
        "--tilt-max",
        "95",
        "--out",
        &d("p.csv"),
    ]);
    assert!(!out.status.success() && stderr(&out).contains("--tilt-max"));
    let out = psdcal([
        "plan",
        "--f",
        "8",
        "--template",
        &template,
        "--snr",
        "40",
        "--out",
        &template,
    ]);
    assert!(
        !out.status.success(),
        "the template must not be overwritten"
    );
}

#[test]
fn plan_with_the_gains_freed_and_next_from_a_calibration_that_fitted_them() {
    // plan --fit …,gains → simulate --poses with unequal gains →
    // calibrate --fit …,gains → plan --next from that calibration: its
    // gains are modelled (freed again, at their fitted values), and
    // holding them (--fit without gains) predicts a smaller σ.
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name).display().to_string();
    assert!(
        psdcal(["simulate", "--snr", "40", "-q", "--out", &d("sim0")])
            .status
            .success()
    );
    let template = &d("sim0/template.csv");
    let plan = |fit: &str, out: &str| plan_lens2(template, &["--fit", fit, "--out", out]);
    let planned = plan("f,cx,cy,k1,k2,gains", &d("poses.csv"));
    let plain = plan("f,cx,cy,k1,k2", &d("plain.csv"));
    for name in ["f", "g_x2", "g_y1", "g_y2"] {
        assert!(
            planned["parameter_sigma"][name].as_f64().unwrap() > 0.0,
            "{name}"
        );
    }
    assert!(plain["parameter_sigma"].get("g_x2").is_none());
    let sigma = |v: &serde_json::Value| v["aoa_sigma_deg"]["rms"].as_f64().unwrap();
    assert!(sigma(&planned) > sigma(&plain));
    let sim = json(&psdcal([
        "simulate",
        "--json",
        "--snr",
        "40",
        "--imbalance",
        "--poses",
        &d("poses.csv"),
        "--out",
        &d("sim"),
    ]));
    assert_eq!(sim["images"], 9);
    let run = psdcal([
        "-q",
        "calibrate",
        "-t",
        &d("sim/template.csv"),
        "-s",
        &d("sim/signals.csv"),
        "--fit",
        "f,cx,cy,k1,k2,gains",
        "--out",
        &d("cal.json"),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let next = |fit: Option<&str>, out: &str| {
        let mut args = vec![
            "plan".to_string(),
            "--json".into(),
            "--next".into(),
            "--calibration".into(),
            d("cal.json"),
            "--template".into(),
            d("sim/template.csv"),
            "--snr".into(),
            "40".into(),
            "--out".into(),
            out.to_string(),
        ];
        if let Some(fit) = fit {
            args.extend(["--fit".to_string(), fit.to_string()]);
        }
        json(&psdcal(args))
    };
    let with_gains = next(None, &d("next.csv"));
    assert_eq!(with_gains["poses"].as_array().unwrap().len(), 1);
    assert!(with_gains["parameter_sigma"]["g_y2"].as_f64().unwrap() > 0.0);
    let before = |v: &serde_json::Value| v["before_aoa_sigma_deg"]["rms"].as_f64().unwrap();
    assert!(sigma(&with_gains) < before(&with_gains));
    let held = next(Some("f,cx,cy,k1,k2"), &d("held.csv"));
    assert!(held["parameter_sigma"].get("g_y2").is_none());
    assert!(before(&held) < before(&with_gains));
}
