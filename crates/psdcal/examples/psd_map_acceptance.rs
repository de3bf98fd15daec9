//! The PSD map's acceptance experiment over ten seeds (see
//! `tests/psd_map_support.rs`): `cargo run --release -p psdcal --example
//! psd_map_acceptance [-- SEEDS [--amplitudes]]`. Prints one row per seed and
//! the pooled RMS angle errors.

#[path = "../tests/psd_map_support.rs"]
mod support;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seeds: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(10);
    let amplitudes = args.iter().any(|a| a == "--amplitudes");
    println!("seed,map_mdeg,l1_mdeg,clean_mdeg,map_error_um,scan_noise_um");
    let mut all = Vec::new();
    for seed in 1..=seeds {
        let e = support::run_seed(seed, amplitudes);
        println!(
            "{seed},{:.3},{:.3},{:.3},{:.3},{:.3}",
            e.map.to_degrees() * 1e3,
            e.l1.to_degrees() * 1e3,
            e.clean.to_degrees() * 1e3,
            e.map_error_mm * 1e3,
            e.scan_noise_mm * 1e3
        );
        all.push(e);
    }
    let p = |f: fn(&support::SeedErrors) -> f64| support::pooled(&all, f).to_degrees() * 1e3;
    println!(
        "pooled RMS angle error (mdeg): map {:.3}, l1 freed {:.3}, no non-linearity {:.3}; \
         map/clean {:.3}, map/l1 {:.3}",
        p(|e| e.map),
        p(|e| e.l1),
        p(|e| e.clean),
        p(|e| e.map) / p(|e| e.clean),
        p(|e| e.map) / p(|e| e.l1)
    );
}
