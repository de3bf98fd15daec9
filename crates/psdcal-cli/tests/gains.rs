//! Amplifier gains from the command line: self-calibration with
//! `calibrate --fit ...,gains`, and the electrical route `psdcal gains` then
//! `calibrate --gains`.

mod common;

use common::{psdcal, stderr, stdout};
use psdcal_io::{read_calibration, read_truth};

#[test]
fn both_routes_recover_the_gains() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim");
    let p = |f: &str| sim.join(f).display().to_string();
    assert!(psdcal([
        "-q",
        "simulate",
        "--lens",
        "2",
        "--snr",
        "50",
        "--imbalance",
        "--seed",
        "6",
        "--out",
        sim.to_str().unwrap()
    ])
    .status
    .success());
    let truth = read_truth(sim.join("truth.json")).unwrap();
    let true_gains = [truth.gains.x2, truth.gains.y1, truth.gains.y2];

    // Self-calibration.
    let cal = p("self.json");
    let run = psdcal([
        "-q",
        "calibrate",
        "-t",
        &p("template.csv"),
        "-s",
        &p("signals.csv"),
        "--fit",
        "f,cx,cy,k1,k2,gains",
        "--out",
        &cal,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let c = read_calibration(&cal).unwrap();
    let g = c.gains.as_ref().unwrap();
    assert!(g.estimated);
    for (name, (est, t)) in ["g_x2", "g_y1", "g_y2"]
        .iter()
        .zip([g.x2, g.y1, g.y2].iter().zip(true_gains))
    {
        let sd = c.std.get(name).unwrap();
        assert!((est - t).abs() < 5.0 * sd, "{name}: {est} ± {sd} vs {t}");
    }
    assert!(c.covariance.parameters.contains(&"g_y2".to_string()));

    // Electrical calibration: equal-current records (the true gains on equal currents, noise-free).
    let equal = p("equal.csv");
    let rows: String = (1..=5)
        .map(|k| {
            format!(
                "{k},1.0,{},{},{}\n",
                true_gains[0], true_gains[1], true_gains[2]
            )
        })
        .collect();
    std::fs::write(&equal, format!("record,vx1,vx2,vy1,vy2\n{rows}")).unwrap();
    let gains_json = p("gains.json");
    let run = psdcal([
        "gains",
        "--signals",
        &equal,
        "--method",
        "equal-current",
        "--out",
        &gains_json,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stdout(&run).contains("g_x2"));
    let cal = p("electrical.json");
    let run = psdcal([
        "-q",
        "calibrate",
        "-t",
        &p("template.csv"),
        "-s",
        &p("signals.csv"),
        "--gains",
        &gains_json,
        "--out",
        &cal,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let c = read_calibration(&cal).unwrap();
    assert!(!c.gains.as_ref().unwrap().estimated);
    let sd = c.std.get("f").unwrap();
    assert!(
        (c.intrinsics.f_mm - 8.0).abs() < 5.0 * sd,
        "f {} ± {sd}",
        c.intrinsics.f_mm
    );
    let sd = c.std.get("cx").unwrap();
    assert!(
        (c.intrinsics.cx_mm - 0.5).abs() < 5.0 * sd,
        "cx {} ± {sd}",
        c.intrinsics.cx_mm
    );

    // Refusals: gains need amplitudes; --gains and a fitted 'gains' exclude each other.
    for args in [
        vec![
            "calibrate",
            "-t",
            "t",
            "-o",
            "o",
            "--fit",
            "f,cx,cy,gains",
            "--out",
            "c",
        ],
        vec![
            "calibrate",
            "-t",
            "t",
            "-s",
            "s",
            "--fit",
            "f,gains",
            "--gains",
            "g",
            "--out",
            "c",
        ],
    ] {
        assert_eq!(psdcal(&args).status.code(), Some(2), "{args:?}");
    }
}

#[test]
fn noise_weighted_self_calibration_is_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim");
    let p = |f: &str| sim.join(f).display().to_string();
    assert!(psdcal([
        "-q",
        "simulate",
        "--snr",
        "40",
        "--imbalance",
        "--seed",
        "9",
        "--out",
        sim.to_str().unwrap()
    ])
    .status
    .success());
    let truth = read_truth(sim.join("truth.json")).unwrap();
    let cal = p("weighted.json");
    let run = psdcal([
        "calibrate",
        "-t",
        &p("template.csv"),
        "-s",
        &p("signals.csv"),
        "--fit",
        "f,cx,cy,k1,k2,gains",
        "--noise",
        "channel-snr",
        "--out",
        &cal,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(
        stdout(&run).contains("weighted by the channel-snr noise model"),
        "{}",
        stdout(&run)
    );
    let c = read_calibration(&cal).unwrap();
    assert_eq!(c.fit.noise, "channel-snr");
    let g = c.gains.as_ref().unwrap();
    for (name, (est, t)) in ["g_x2", "g_y1", "g_y2"]
        .iter()
        .zip(
            [g.x2, g.y1, g.y2]
                .iter()
                .zip([truth.gains.x2, truth.gains.y1, truth.gains.y2]),
        )
    {
        let sd = c.std.get(name).unwrap();
        assert!((est - t).abs() < 5.0 * sd, "{name}: {est} ± {sd} vs {t}");
    }
    // A model the CLI does not know is refused by the argument parser.
    let run = psdcal([
        "calibrate",
        "-t",
        &p("template.csv"),
        "-s",
        &p("signals.csv"),
        "--noise",
        "gaussian",
        "--out",
        &p("x.json"),
    ]);
    assert!(!run.status.success());
    assert!(stderr(&run).contains("channel-snr"), "{}", stderr(&run));
}

/// Unequal gains fitted without gains: `gain_imbalance_suspected` on stderr
/// (`warning: …`), in `--json` and in calibration.json; fitted with the
/// gains, not raised.
#[test]
fn imbalance_without_gains_is_diagnosed() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim");
    let p = |f: &str| sim.join(f).display().to_string();
    let run = psdcal([
        "-q",
        "simulate",
        "--lens",
        "1",
        "--snr",
        "60",
        "--imbalance",
        "--images",
        "12",
        "--seed",
        "3",
        "--out",
        sim.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let codes = |v: &serde_json::Value| -> Vec<String> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|d| d["code"].as_str().unwrap().to_string())
            .collect()
    };
    let cal = p("plain.json");
    let run = psdcal([
        "calibrate",
        "--json",
        "-t",
        &p("template.csv"),
        "-s",
        &p("signals.csv"),
        "--out",
        &cal,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(
        err.lines()
            .any(|l| l.starts_with("warning: ") && l.contains("--fit f,cx,cy,k1,k2,gains")),
        "{err}"
    );
    let summary: serde_json::Value = serde_json::from_str(&stdout(&run)).unwrap();
    assert!(codes(&summary["diagnostics"]).contains(&"gain_imbalance_suspected".to_string()));
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&cal).unwrap()).unwrap();
    assert_eq!(file["diagnostics"], summary["diagnostics"]);

    let cal = p("gains.json");
    let run = psdcal([
        "calibrate",
        "--json",
        "-t",
        &p("template.csv"),
        "-s",
        &p("signals.csv"),
        "--fit",
        "f,cx,cy,k1,k2,gains",
        "--out",
        &cal,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let summary: serde_json::Value = serde_json::from_str(&stdout(&run)).unwrap();
    assert!(!codes(&summary["diagnostics"]).contains(&"gain_imbalance_suspected".to_string()));
}
