//! In-situ calibration from surveyed emitters (docs/model.md §8.4): seeded
//! trials of psdcal-sim's room scenes, calibrated from the DLT start and
//! from the truth; prints the AoA errors, σ(f) against the spread of f over
//! the seeds, and the predicted AoA σ against the measured AoA errors.
//!
//! `cargo run --release -p psdcal-study --example insitu -- [--trials N]
//! [--emitters N] [--orientations N] [--survey-sigma MM] [--snr DB] [--wide]`
//! `--guide` prints the guide's table (README, "In-situ calibration").

use psdcal_sim::insitu::InSituOptions;
use psdcal_study::insitu::{predicted_aoa_sigma, run_trial, InSituTrial};
use rayon::prelude::*;

fn arg(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

struct Row {
    trials: usize,
    failed: usize,
    median_ratio: f64,
    max_ratio: f64,
    above: usize,
    stuck: usize,
    z_f: f64,
    aoa_rms_deg: f64,
    aoa_truth_rms_deg: f64,
    predicted_aoa_deg: f64,
    sd_f: f64,
    mean_sigma_f: f64,
    pose_deg: f64,
    position_mm: f64,
}

fn run(options: &InSituOptions, wide: bool, trials: usize, base: u64) -> Row {
    let results: Vec<Option<InSituTrial>> = (0..trials as u64)
        .into_par_iter()
        .map(|k| run_trial(options, wide, base + k).ok())
        .collect();
    let ok: Vec<&InSituTrial> = results.iter().flatten().collect();
    let n = ok.len() as f64;
    let mut ratios: Vec<f64> = ok
        .iter()
        .map(|t| t.aoa_error / t.aoa_error_from_truth)
        .collect();
    ratios.sort_by(f64::total_cmp);
    let rms = |v: Vec<f64>| (v.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    let df: Vec<f64> = ok
        .iter()
        .map(|t| t.fit.model.get("f").unwrap_or(f64::NAN) - t.true_f)
        .collect();
    let mean_df = df.iter().sum::<f64>() / n;
    let sd_f = (df.iter().map(|d| (d - mean_df).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    Row {
        trials,
        failed: trials - ok.len(),
        above: ratios.iter().filter(|r| **r > 1.3).count(),
        stuck: ok
            .iter()
            .filter(|t| {
                t.aoa_error > 1.3 * t.aoa_error_from_truth
                    && t.fit.cost > t.cost_from_truth * (1.0 + 1e-9)
            })
            .count(),
        z_f: rms(ok
            .iter()
            .map(|t| {
                (t.fit.model.get("f").unwrap_or(f64::NAN) - t.true_f)
                    / t.fit.covariance.std("f").unwrap_or(f64::NAN)
            })
            .collect()),
        median_ratio: ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN),
        max_ratio: ratios.last().copied().unwrap_or(f64::NAN),
        aoa_rms_deg: rms(ok.iter().map(|t| t.aoa_error).collect()).to_degrees(),
        aoa_truth_rms_deg: rms(ok.iter().map(|t| t.aoa_error_from_truth).collect()).to_degrees(),
        predicted_aoa_deg: rms(ok
            .iter()
            .map(|t| {
                std::f64::consts::SQRT_2
                    * predicted_aoa_sigma(&t.fit.model, &t.fit.covariance, &options.geometry)
            })
            .collect())
        .to_degrees(),
        sd_f,
        mean_sigma_f: ok
            .iter()
            .map(|t| t.fit.covariance.std("f").unwrap_or(f64::NAN))
            .sum::<f64>()
            / n,
        pose_deg: rms(ok.iter().map(|t| t.pose_angle_error).collect()).to_degrees(),
        position_mm: rms(ok.iter().map(|t| t.position_error_mm).collect()),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let trials: usize = arg(&args, "--trials").map_or(100, |v| v.parse().expect("--trials N"));
    let wide = args.iter().any(|a| a == "--wide");
    let mut options = InSituOptions::default();
    if let Some(v) = arg(&args, "--emitters") {
        options.emitters = v.parse().expect("--emitters N");
    }
    if let Some(v) = arg(&args, "--orientations") {
        options.orientations = v.parse().expect("--orientations N");
    }
    if let Some(v) = arg(&args, "--survey-sigma") {
        options.survey_sigma_mm = v.parse().expect("--survey-sigma MM");
    }
    if let Some(v) = arg(&args, "--snr") {
        options.snr_db = v.parse().expect("--snr DB");
    }
    println!(
        "| emitters | orientations | survey σ (mm) | trials (failed) | AoA err RMS (°) | from truth (°) | median / max ratio (> 1.3; of them start failures) | predicted AoA σ (°) | σ(f) reported (mm) | sd(f) over seeds (mm) | RMS (f̂ − f)/σ(f) | pose err (°) | position err (mm) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let configs: Vec<(usize, usize, f64)> = if args.iter().any(|a| a == "--guide") {
        let mut c = Vec::new();
        for s in [0.5, 2.0, 5.0] {
            for (e, o) in [(16, 1), (24, 1), (16, 3), (24, 3)] {
                c.push((e, o, s));
            }
        }
        c
    } else {
        vec![(
            options.emitters,
            options.orientations,
            options.survey_sigma_mm,
        )]
    };
    for (e, o, s) in configs {
        let opts = InSituOptions {
            emitters: e,
            orientations: o,
            survey_sigma_mm: s,
            ..options.clone()
        };
        let r = run(&opts, wide, trials, 1000);
        let what = |v: String| if wide { "wide".to_string() } else { v };
        println!(
            "| {} | {} | {} | {} ({}) | {:.4} | {:.4} | {:.3} / {:.3} ({}; {}) | {:.4} | {:.4} | {:.4} | {:.2} | {:.3} | {:.1} |",
            what(e.to_string()),
            what(o.to_string()),
            what(s.to_string()),
            r.trials,
            r.failed,
            r.aoa_rms_deg,
            r.aoa_truth_rms_deg,
            r.median_ratio,
            r.max_ratio,
            r.above,
            r.stuck,
            r.predicted_aoa_deg,
            r.mean_sigma_f,
            r.sd_f,
            r.z_f,
            r.pose_deg,
            r.position_mm
        );
    }
}
