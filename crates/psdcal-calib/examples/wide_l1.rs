//! The free-`l1` calibration judged on wide scenarios
//! (`psdcal_testkit::wide`, judged by `tests/support/wide.rs`): does
//! `calibrate` with `f, cx, cy, k1, k2, l1` freed ever end above the cost of
//! the same fit with `l1` held at its true value?
//!
//! ```text
//! cargo run --release -p psdcal-calib --example wide_l1 -- \
//!     [--n 1000] [--start 0] [--threads 2] [--csv wide_l1.csv] [--list]
//! ```
//!
//! Scenario `i` (for `i` in `start..start + n`) is drawn from
//! `ChaCha8Rng::seed_from_u64(WIDE_SEED_BASE + i)` whatever the threads, so
//! the CSV (one row per scenario, in index order, no timing) is the same for
//! any `--threads`. `--list` prints the scenarios without fitting them.

#[path = "../tests/support/mod.rs"]
mod support;

use psdcal_testkit::WideScenario;
use rayon::prelude::*;
use support::wide::{judge, Verdict};

struct Args {
    n: u64,
    start: u64,
    threads: usize,
    csv: Option<String>,
    list: bool,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        n: 1000,
        start: 0,
        threads: 0,
        csv: None,
        list: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match a.as_str() {
            "--n" => args.n = value("--n")?.parse().map_err(|e| format!("--n: {e}"))?,
            "--start" => {
                args.start = value("--start")?
                    .parse()
                    .map_err(|e| format!("--start: {e}"))?
            }
            "--threads" => {
                args.threads = value("--threads")?
                    .parse()
                    .map_err(|e| format!("--threads: {e}"))?
            }
            "--csv" => args.csv = Some(value("--csv")?),
            "--list" => args.list = true,
            other => return Err(format!("unknown argument '{other}'")),
        }
    }
    Ok(args)
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

fn list(range: std::ops::Range<u64>) {
    println!("index lens f l1 sigma_mm images points kept region_centre half_width scale");
    for i in range {
        let s = WideScenario::draw(i);
        println!(
            "{i} {} {:.3} {:+.3e} {:.2e} {} {} {:.2} ({:+.2},{:+.2}) {:.2} {:.2}",
            s.lens.number(),
            s.truth.intrinsics.f,
            s.truth.distortion.l1,
            s.sigma_mm,
            s.images.len(),
            s.point_count(),
            s.kept_fraction(),
            s.region.centre.x,
            s.region.centre.y,
            s.region.half_width,
            s.template_scale
        );
    }
}

fn summary(verdicts: &[Verdict]) {
    let n = verdicts.len();
    let failed: Vec<&Verdict> = verdicts.iter().filter(|v| !v.passes()).collect();
    println!("scenarios: {n}");
    for v in &failed {
        let cost = |r: &Result<support::wide::Fit, String>| {
            r.as_ref()
                .map_or_else(|e| format!("error: {e}"), |f| format!("{:.6e}", f.cost))
        };
        println!(
            "FAIL index {} (lens {}, l1 {:+.3e}, σ {:.2e} mm, {} images, {} points): \
             cost {} against l1 fixed at truth {} (ratio {:.6}); l1 {} (σ {}), centre off {:.3} mm; \
             from truth with l1 freed {}",
            v.index,
            v.lens,
            v.l1_true,
            v.sigma_mm,
            v.images,
            v.points,
            cost(&v.automatic),
            cost(&v.fixed_at_truth),
            v.cost_ratio(),
            v.automatic
                .as_ref()
                .map_or("-".into(), |a| format!("{:+.4e}", a.l1)),
            v.l1_std.map_or("-".into(), |s| format!("{s:.2e}")),
            v.centre_error(),
            cost(&v.free_from_truth),
        );
    }
    let classes = [
        (
            "lens 1",
            Box::new(|v: &Verdict| v.lens == 1) as Box<dyn Fn(&Verdict) -> bool>,
        ),
        ("lens 2", Box::new(|v: &Verdict| v.lens == 2)),
        ("l1 = 0", Box::new(|v: &Verdict| v.l1_true == 0.0)),
        ("l1 > 0", Box::new(|v: &Verdict| v.l1_true > 0.0)),
        ("l1 < 0", Box::new(|v: &Verdict| v.l1_true < 0.0)),
        ("noise-free", Box::new(|v: &Verdict| v.sigma_mm == 0.0)),
        ("noisy", Box::new(|v: &Verdict| v.sigma_mm > 0.0)),
    ];
    for (name, select) in &classes {
        let of: Vec<_> = verdicts.iter().filter(|v| select(v)).collect();
        let fails = of.iter().filter(|v| !v.passes()).count();
        println!("  {name:<10} {fails} failures of {}", of.len());
    }
    let errors = verdicts.iter().filter(|v| v.automatic.is_err()).count();
    let no_reference = verdicts
        .iter()
        .filter(|v| v.fixed_at_truth.is_err())
        .count();
    println!(
        "failures: {} of {n} ({errors} calibrate errors); references that failed: {no_reference}",
        failed.len()
    );
    let mut ratios: Vec<f64> = verdicts
        .iter()
        .map(|v| v.cost_ratio())
        .filter(|r| r.is_finite())
        .collect();
    ratios.sort_by(f64::total_cmp);
    println!(
        "cost ratio (automatic / l1 fixed at truth): min {:.6} p1 {:.6} median {:.6} p99 {:.6} max {:.6}",
        quantile(&ratios, 0.0),
        quantile(&ratios, 0.01),
        quantile(&ratios, 0.5),
        quantile(&ratios, 0.99),
        quantile(&ratios, 1.0)
    );
    let mut worst: Vec<&Verdict> = verdicts
        .iter()
        .filter(|v| v.cost_ratio().is_finite())
        .collect();
    worst.sort_by(|a, b| b.cost_ratio().total_cmp(&a.cost_ratio()));
    print!("worst ratios:");
    for v in worst.iter().take(10) {
        print!(" {}:{:.6}", v.index, v.cost_ratio());
    }
    println!();
    let same = verdicts
        .iter()
        .filter(|v| v.same_as_truth_start() == Some(true))
        .count();
    let judged = verdicts
        .iter()
        .filter(|v| v.same_as_truth_start().is_some())
        .count();
    println!("same minimum as the free-l1 fit from the truth: {same} of {judged}");
    let below = verdicts
        .iter()
        .filter(|v| match (&v.automatic, &v.free_from_truth) {
            (Ok(a), Ok(c)) => a.cost < c.cost * (1.0 - 1e-6) - 1e-18 * v.points as f64,
            _ => false,
        })
        .count();
    println!("automatic fit below the free-l1 fit from the truth: {below}");
    let secs: Vec<f64> = verdicts.iter().map(|v| v.elapsed.as_secs_f64()).collect();
    let slowest = verdicts
        .iter()
        .max_by(|a, b| a.elapsed.cmp(&b.elapsed))
        .map_or(0, |v| v.index);
    println!(
        "time per calibrate: mean {:.3} s, max {:.3} s (index {slowest})",
        secs.iter().sum::<f64>() / secs.len().max(1) as f64,
        secs.iter().copied().fold(0.0, f64::max)
    );
}

fn main() {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let range = args.start..args.start + args.n;
    if args.list {
        list(range);
        return;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads)
        .build()
        .expect("thread pool");
    let verdicts: Vec<Verdict> = pool.install(|| {
        range
            .into_par_iter()
            .map(|i| judge(&WideScenario::draw(i)))
            .collect()
    });
    summary(&verdicts);
    if let Some(path) = args.csv {
        let mut text = String::from(Verdict::CSV_HEADER);
        text.push('\n');
        for v in &verdicts {
            text.push_str(&v.csv_row());
            text.push('\n');
        }
        std::fs::write(&path, text).unwrap_or_else(|e| panic!("writing {path}: {e}"));
        println!("wrote {path}");
    }
}
