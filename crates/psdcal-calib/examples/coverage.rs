//! Coverage of the reported uncertainty (issue 12, point 4): over seeded
//! trials (`tests/support/coverage.rs`), the fraction of (parameter, trial)
//! pairs with |error| ≤ kσ for k = 1, 2, 3, per parameter, and the ratio of
//! the empirical spread to the mean reported σ; for the reported σ and for
//! the single-σ² linear estimate `σ² (JᵀJ)⁻¹` side by side.
//!
//! ```text
//! cargo run --release -p psdcal-calib --example coverage -- \
//!     [--wide 200] [--hard 40] [--sigma 0.05] [--threads 2]
//! ```
//!
//! `--wide n`: wide scenarios 0..n as drawn (noise-free ones skipped);
//! `--hard n`: n re-noised trials at `--sigma` mm on the geometry of the
//! first lens-1 and the first lens-2 wide scenario with 9–12 images. The
//! output is the same for any `--threads`.

#[path = "../tests/support/mod.rs"]
mod support;

use psdcal_testkit::wide::Lens;
use psdcal_testkit::WideScenario;
use rayon::prelude::*;
use support::coverage::{covered, hard_geometry, renoised, Trial, FREE, HARD_SEED_BASE};

struct Args {
    wide: u64,
    hard: u64,
    sigma: f64,
    threads: usize,
    verdict: bool,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        wide: 200,
        hard: 40,
        sigma: 0.05,
        threads: 0,
        verdict: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match a.as_str() {
            "--wide" => args.wide = value("--wide")?.parse().map_err(|e| format!("{e}"))?,
            "--hard" => args.hard = value("--hard")?.parse().map_err(|e| format!("{e}"))?,
            "--sigma" => args.sigma = value("--sigma")?.parse().map_err(|e| format!("{e}"))?,
            "--threads" => {
                args.threads = value("--threads")?.parse().map_err(|e| format!("{e}"))?
            }
            "--verdict" => args.verdict = true,
            other => return Err(format!("unknown argument '{other}'")),
        }
    }
    Ok(args)
}

fn spread(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

fn report(name: &str, trials: &[Trial], same_geometry: bool) {
    let ok: Vec<&Trial> = trials.iter().filter(|t| t.result.is_ok()).collect();
    println!(
        "== {name}: {} trials, {} calibrated",
        trials.len(),
        ok.len()
    );
    for (label, z_of) in [
        ("reported", Trial::z as fn(&Trial) -> Vec<f64>),
        ("linear  ", Trial::z_linear),
    ] {
        let all: Vec<f64> = ok.iter().flat_map(|t| z_of(t)).collect();
        print!(
            "  {label} all: ≤1σ {:.3} ≤2σ {:.3} ≤3σ {:.3} |",
            covered(&all, 1.0),
            covered(&all, 2.0),
            covered(&all, 3.0)
        );
        for (k, p) in FREE.iter().enumerate() {
            let z: Vec<f64> = ok.iter().map(|t| z_of(t)[k]).collect();
            print!(" {} {:.3}", p.name(), covered(&z, 3.0));
        }
        println!();
    }
    if same_geometry && ok.len() > 2 {
        for (k, p) in FREE.iter().enumerate() {
            let e: Vec<f64> = ok.iter().map(|t| t.errors[k]).collect();
            let (mean, sd) = spread(&e);
            let mean_std = ok.iter().map(|t| t.std[k]).sum::<f64>() / ok.len() as f64;
            let mean_lin = ok.iter().map(|t| t.std_linear[k]).sum::<f64>() / ok.len() as f64;
            println!(
                "  {:<3} spread {sd:.3e} bias {mean:+.3e} (bias/spread {:+.2}) | spread/σ reported {:.3} linear {:.3}",
                p.name(),
                mean / sd,
                sd / mean_std,
                sd / mean_lin
            );
        }
    }
    let reliable: Vec<&&Trial> = ok.iter().filter(|t| !t.flagged()).collect();
    let z: Vec<f64> = reliable.iter().flat_map(|t| t.z()).collect();
    println!(
        "  flagged unreliable: {} of {}; coverage of the others ≤3σ {:.3} ({} pairs)",
        ok.len() - reliable.len(),
        ok.len(),
        covered(&z, 3.0),
        z.len()
    );
    let departure = |t: &Trial| {
        t.result.as_ref().map_or(f64::NAN, |r| {
            r.linearity
                .parameters
                .iter()
                .map(|p| p.departure())
                .fold(0.0, f64::max)
        })
    };
    let mut deps: Vec<f64> = ok.iter().map(|t| departure(t)).collect();
    deps.sort_by(f64::total_cmp);
    if !deps.is_empty() {
        println!(
            "  max|ρ−1| per trial: median {:.3} p90 {:.3} max {:.3}",
            deps[deps.len() / 2],
            deps[deps.len() * 9 / 10],
            deps[deps.len() - 1]
        );
    }
    let worst: Vec<String> = ok
        .iter()
        .filter(|t| t.z().iter().any(|z| *z > 3.0))
        .map(|t| {
            let z = t.z();
            let (k, m) = z
                .iter()
                .enumerate()
                .fold((0, 0.0), |a, (k, v)| if *v > a.1 { (k, *v) } else { a });
            format!(
                "{}:{}={m:.1}(σ{:.0e},n{},ρ{:.2})",
                t.index,
                FREE[k].name(),
                t.sigma_mm,
                t.images,
                departure(t)
            )
        })
        .collect();
    println!("  beyond 3σ: {}", worst.join(" "));
    for t in trials.iter().filter(|t| t.result.is_err()) {
        println!("  failed {}: {}", t.index, t.result.as_ref().err().unwrap());
    }
}

fn main() {
    let args = parse().unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2)
    });
    if let Ok(i) = std::env::var("INSPECT") {
        for i in i.split(',') {
            inspect(i.parse().unwrap());
        }
        return;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let wide: Vec<Trial> = (0..args.wide)
            .into_par_iter()
            .filter_map(|i| {
                let s = WideScenario::draw(i);
                (s.sigma_mm > 0.0)
                    .then(|| Trial::run(i, &s, s.sigma_mm, &support::wide::data(&s), |_| {}))
            })
            .collect();
        report("wide (as drawn, noisy, l1 known)", &wide, false);
        let by_lens =
            |lens: u8| -> Vec<Trial> { wide.iter().filter(|t| t.lens == lens).cloned().collect() };
        report("wide lens 1", &by_lens(1), false);
        report("wide lens 2", &by_lens(2), false);
        for lens in [Lens::One, Lens::Two] {
            let index = hard_geometry(lens);
            let s = WideScenario::draw(index);
            let trials: Vec<Trial> = (0..args.hard)
                .into_par_iter()
                .map(|t| {
                    let d = renoised(&s, args.sigma, HARD_SEED_BASE + t);
                    Trial::run(t, &s, args.sigma, &d, |_| {})
                })
                .collect();
            report(
                &format!(
                    "hard: lens {} (scenario {index}, {} images), σ {} mm",
                    lens.number(),
                    s.images.len(),
                    args.sigma
                ),
                &trials,
                true,
            );
        }
    });
}

#[allow(dead_code)]
fn inspect(i: u64) {
    let s = WideScenario::draw(i);
    let d = support::wide::data(&s);
    let t = Trial::run(i, &s, s.sigma_mm, &d, |_| {});
    let r = t.result.as_ref().unwrap();
    println!("scenario {i}: truth {:?}", s.truth);
    println!("est {:?}", r.sensor_model());
    println!("errors {:?}\nstd {:?}\nz {:?}", t.errors, t.std, t.z());
    let o = support::coverage::options(&s.truth);
    let from_truth = psdcal_calib::refine(
        &d,
        psdcal_model::Model::standard(&s.truth),
        &s.poses(),
        &o.refine,
    )
    .unwrap();
    println!(
        "cost {:.6e}, from truth {:.6e}, est from truth {:?}",
        r.cost,
        from_truth.cost,
        from_truth.sensor_model()
    );
    println!(
        "warnings {:?} region {:?} scale {}",
        r.warnings, s.region, s.template_scale
    );
}
