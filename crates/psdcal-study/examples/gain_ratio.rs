//! What self-calibrating the amplifier gains costs in angle-of-arrival
//! accuracy (issue 7): for each seed, lens 2 at 40 dB with nine images, the
//! held-out AoA RMS error of a calibration that frees the gains on
//! unbalanced data, divided by that of a plain calibration on the same
//! seed's balanced data (same poses, same noise draws).
//!
//! ```sh
//! cargo run --release -p psdcal-study --example gain_ratio -- [FIRST_SEED] [SEEDS] [template|image] [uniform|channel-snr|channel-floor]
//! ```
//!
//! Defaults: seeds 100…299 (those of `tests/gains.rs`), template-plane
//! cost, uniform weighting. Prints the median per-seed ratio, the medians
//! and RMS of both errors, and the medians of disjoint blocks of 30 seeds
//! (their spread is what a 30-seed experiment would see).

use psdcal_calib::{calibrate, CalibrateOptions, CostKind, NoiseModel, RefineOptions};
use psdcal_model::ChannelGains;
use psdcal_sim::{simulate, Lens, SimulationOptions};
use psdcal_study::SimulationData;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |k: usize, default: &str| args.get(k).cloned().unwrap_or_else(|| default.into());
    let (Ok(first), Ok(seeds)) = (arg(0, "100").parse::<u64>(), arg(1, "200").parse::<u64>())
    else {
        eprintln!("error: FIRST_SEED and SEEDS must be non-negative integers");
        std::process::exit(2);
    };
    let cost = match arg(2, "template").as_str() {
        "template" => CostKind::Template,
        "image" => CostKind::Image,
        other => {
            eprintln!("error: unknown cost '{other}' (template or image)");
            std::process::exit(2);
        }
    };
    let noise = match arg(3, "uniform").as_str() {
        "uniform" => NoiseModel::Uniform,
        "channel-snr" => NoiseModel::ChannelSnr,
        "channel-floor" => NoiseModel::ChannelFloor,
        other => {
            eprintln!("error: unknown noise model '{other}' (uniform, channel-snr, channel-floor)");
            std::process::exit(2);
        }
    };
    if seeds == 0 {
        eprintln!("error: at least one seed");
        std::process::exit(2);
    }
    let options = |fit_gains| CalibrateOptions {
        refine: RefineOptions {
            cost,
            noise,
            fit_gains,
            ..RefineOptions::default()
        },
        ..CalibrateOptions::default()
    };
    let per_seed: Vec<Option<(f64, f64)>> = (first..first + seeds)
        .into_par_iter()
        .map(|seed| {
            let unbalanced = SimulationOptions {
                lens: Lens::Two,
                snr_db: Some(40.0),
                imbalance: true,
                ..SimulationOptions::default()
            };
            let balanced = SimulationOptions {
                imbalance: false,
                ..unbalanced.clone()
            };
            let sim = simulate(&unbalanced, &mut ChaCha8Rng::seed_from_u64(seed)).ok()?;
            let reference = simulate(&balanced, &mut ChaCha8Rng::seed_from_u64(seed)).ok()?;
            let fitted = calibrate(&sim.calibration_data(), &options(true)).ok()?;
            let plain = calibrate(&reference.calibration_data(), &options(false)).ok()?;
            Some((
                sim.aoa_rms_error(&fitted.sensor_model(), &fitted.gains?),
                reference.aoa_rms_error(&plain.sensor_model(), &ChannelGains::UNIT),
            ))
        })
        .collect();
    let failed = per_seed.iter().filter(|r| r.is_none()).count();
    let pairs: Vec<(f64, f64)> = per_seed.into_iter().flatten().collect();
    if pairs.is_empty() {
        eprintln!("error: every calibration failed");
        std::process::exit(1);
    }
    let ratios: Vec<f64> = pairs.iter().map(|(a, b)| a / b).collect();
    let with_gains: Vec<f64> = pairs.iter().map(|p| p.0.to_degrees()).collect();
    let balanced: Vec<f64> = pairs.iter().map(|p| p.1.to_degrees()).collect();
    println!(
        "{} seeds from {first} ({failed} failed), {cost:?} cost, {} weighting",
        pairs.len(),
        noise.name()
    );
    println!("median per-seed AoA ratio  {:.3}", median(&ratios));
    println!(
        "median AoA error           {:.4}° with gains freed, {:.4}° balanced",
        median(&with_gains),
        median(&balanced)
    );
    println!(
        "RMS AoA error              {:.4}° with gains freed, {:.4}° balanced (ratio {:.3})",
        rms(&with_gains),
        rms(&balanced),
        rms(&with_gains) / rms(&balanced)
    );
    let blocks: Vec<String> = ratios
        .chunks_exact(30)
        .map(|b| format!("{:.3}", median(b)))
        .collect();
    if !blocks.is_empty() {
        println!("30-seed block medians      {}", blocks.join(" "));
    }
}
