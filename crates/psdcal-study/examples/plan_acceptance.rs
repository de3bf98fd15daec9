//! Issue 16's acceptance at full size: planned against random poses over
//! seeded simulations (lens 2, 40 dB, nine images, the 14-LED template).
//!
//! `cargo run --release -p psdcal-study --example plan_acceptance -- [TRIALS] [IMAGES] [gains]`
//! (default 30 trials, 9 images; `gains`: the data with the study's gain
//! imbalance, the gains freed in the plan and in every calibration).

use psdcal_calib::plan::{plan, PlanOptions};
use psdcal_sim::SimulationOptions;
use psdcal_study::planned::{compare_poses, median, predicted_rms, rms, simulation_setup};

fn main() {
    let mut args = std::env::args().skip(1);
    let trials: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(30);
    let images: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(9);
    let gains = args.next().is_some_and(|a| a == "gains");
    let options = SimulationOptions {
        images,
        imbalance: gains,
        ..SimulationOptions::default()
    };
    let setup = simulation_setup(&options, gains);
    let start = std::time::Instant::now();
    let planned = match plan(
        &setup,
        &PlanOptions {
            images,
            ..PlanOptions::default()
        },
    ) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("plan failed: {e}");
            std::process::exit(1);
        }
    };
    let elapsed = start.elapsed().as_secs_f64();
    let poses: Vec<_> = planned.poses.iter().map(|c| c.pose).collect();
    for c in &planned.poses {
        println!(
            "pose: distance {:.0} mm, tilt {:.1}°, t = ({:.1}, {:.1}, {:.1})",
            c.distance_mm,
            c.tilt.to_degrees(),
            c.pose.t.x,
            c.pose.t.y,
            c.pose.t.z
        );
    }
    let predicted = predicted_rms(&setup, &poses, &options).unwrap_or(f64::NAN);
    println!(
        "plan: {images} poses from {} candidates in {elapsed:.2} s; predicted AoA σ RMS {:.5}°, max {:.5}° (active area); \
         RMS {:.5}° on the held-out grid",
        planned.candidates,
        planned.prediction.rms.to_degrees(),
        planned.prediction.max.to_degrees(),
        predicted.to_degrees()
    );
    let results = compare_poses(&options, &poses, trials, 1000, gains);
    let failed = |f: fn(&psdcal_study::planned::PlanTrial) -> Option<f64>| {
        results.iter().filter(|t| f(t).is_none()).count()
    };
    let (mr, mp) = (
        median(results.iter().map(|t| t.random)).unwrap_or(f64::NAN),
        median(results.iter().map(|t| t.planned)).unwrap_or(f64::NAN),
    );
    let spread = rms(results.iter().map(|t| t.planned)).unwrap_or(f64::NAN);
    println!(
        "{trials} trials: median AoA error random {:.5}° ({} failed), planned {:.5}° ({} failed); ratio {:.3}",
        mr.to_degrees(),
        failed(|t| t.random),
        mp.to_degrees(),
        failed(|t| t.planned),
        mp / mr
    );
    println!(
        "planned: simulated RMS AoA error {:.5}°, predicted {:.5}°, predicted/simulated {:.3}",
        spread.to_degrees(),
        predicted.to_degrees(),
        predicted / spread
    );
}
