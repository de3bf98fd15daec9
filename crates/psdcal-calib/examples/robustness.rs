//! The robustness experiment over many scenarios:
//! `cargo run --release -p psdcal-calib --example robustness -- 1000`.

#[path = "../tests/support/mod.rs"]
mod support;

fn main() {
    let n: u64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1000);
    let mut failures = 0;
    let mut by_kind = std::collections::BTreeMap::new();
    for seed in 0..n {
        let o = support::robustness::run(seed);
        let e = by_kind.entry((o.lens, o.psd)).or_insert((0u32, 0u32));
        e.0 += 1;
        if !o.success() {
            failures += 1;
            e.1 += 1;
            println!("miss: {o:?}");
        }
    }
    for ((lens, psd), (count, miss)) in by_kind {
        println!("lens {lens}, PSD distortion {psd}: {miss} misses of {count}");
    }
    println!(
        "global minimum reached in {} of {n} scenarios ({:.2} %)",
        n - failures,
        100.0 * (n - failures) as f64 / n as f64
    );
}
