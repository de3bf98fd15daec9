//! `psdcal simulate`: one simulated data set written as psdcal's input files
//! plus truth.json.

use psdcal_io::{
    write_observations, write_signals, write_template, write_truth, IntrinsicsRecord,
    ObservationRow, SensorSize, SignalRowOut, SimulationSettings, TemplateLed, TrueGains, TruePose,
    Truth, TRUTH_FORMAT, TRUTH_VERSION,
};
use psdcal_sim::{simulate, Simulation, SimulationOptions};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::cli::Output;
use crate::cli_sim::SimulateArgs;

/// Runs `simulate`.
pub fn run(args: &SimulateArgs, output: Output) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out).map_err(|e| {
        anyhow::anyhow!(
            "cannot create the output folder {}: {e}",
            args.out.display()
        )
    })?;
    let options = SimulationOptions {
        lens: args.lens,
        snr_db: args.snr,
        imbalance: args.imbalance,
        psd_distortion: args.psd_distortion,
        images: args.images,
        template: args.template,
        chain: crate::cli_sim::chain_with_record(args.record_cycles)?,
        ..SimulationOptions::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let sim = simulate(&options, &mut rng)?;
    let what = describe(args);
    write_template(
        args.out.join("template.csv"),
        &format!("{what}\nTemplate {} (mm).", args.template.name()),
        &template_leds(&sim),
    )?;
    let observations: Vec<ObservationRow> = sim
        .images
        .iter()
        .flat_map(|im| {
            im.points.iter().map(|p| ObservationRow {
                image: im.id.clone(),
                led: led_id(p.led),
                x_mm: p.measured.x,
                y_mm: p.measured.y,
            })
        })
        .collect();
    write_observations(
        args.out.join("observations.csv"),
        &format!("{what}\nImpact points from the demodulated amplitudes (balanced formula)."),
        &observations,
    )?;
    let signals: Vec<SignalRowOut> = sim
        .images
        .iter()
        .flat_map(|im| {
            im.points.iter().map(|p| SignalRowOut {
                image: im.id.clone(),
                led: led_id(p.led),
                amplitudes: p.amplitudes,
            })
        })
        .collect();
    write_signals(
        args.out.join("signals.csv"),
        &format!("{what}\nDemodulated electrode amplitudes (V)."),
        &signals,
    )?;
    write_truth(args.out.join("truth.json"), &truth(&sim, args))?;
    match output {
        Output::Quiet => {}
        Output::Json => println!(
            "{}",
            serde_json::json!({
                "out": args.out.display().to_string(),
                "images": sim.images.len(),
                "points": observations.len(),
                "files": ["template.csv", "observations.csv", "signals.csv", "truth.json"],
            })
        ),
        Output::Text => {
            println!("{what}");
            println!(
                "wrote {0}/template.csv, {0}/observations.csv, {0}/signals.csv, {0}/truth.json ({1} images, {2} points)",
                args.out.display(),
                sim.images.len(),
                observations.len()
            );
        }
    }
    Ok(())
}

fn led_id(index: usize) -> String {
    format!("{}", index + 1)
}

fn describe(args: &SimulateArgs) -> String {
    format!(
        "Simulated by psdcal {}: lens {}, {}{}{}, {} images, seed {}.",
        env!("CARGO_PKG_VERSION"),
        args.lens.number(),
        args.snr
            .map_or("no noise".to_string(), |s| format!("{s} dB SNR")),
        if args.imbalance {
            ", gain imbalance"
        } else {
            ""
        },
        if args.psd_distortion {
            ", PSD distortion"
        } else {
            ""
        },
        args.images,
        args.seed
    ) + &if args.record_cycles == crate::cli_sim::DEFAULT_RECORD_CYCLES {
        String::new()
    } else {
        format!(" Records of {} cycles.", args.record_cycles)
    }
}

fn template_leds(sim: &Simulation) -> Vec<TemplateLed> {
    sim.template
        .leds
        .iter()
        .enumerate()
        .map(|(i, p)| TemplateLed {
            id: led_id(i),
            x_mm: p.x,
            y_mm: p.y,
            lines: sim
                .template
                .lines
                .iter()
                .zip(&sim.template.line_names)
                .filter(|(leds, _)| leds.contains(&i))
                .map(|(_, name)| name.clone())
                .collect(),
        })
        .collect()
}

fn truth(sim: &Simulation, args: &SimulateArgs) -> Truth {
    let chain = sim.options.chain.config();
    let m = &sim.truth;
    Truth {
        format: TRUTH_FORMAT.into(),
        version: TRUTH_VERSION,
        simulation: SimulationSettings {
            seed: args.seed,
            lens: args.lens.number(),
            snr_db: args.snr,
            imbalance: args.imbalance,
            psd_distortion: args.psd_distortion,
            template: args.template.name().into(),
            images: args.images,
            photocurrent_a: sim.options.photocurrent_a,
            f0_hz: chain.f0_hz,
            sample_rate_hz: chain.sample_rate_hz,
            bandwidth_hz: chain.bandwidth_hz,
            filter_order: chain.filter_order,
            record_s: chain.record_cycles as f64 / chain.f0_hz,
            demodulation: format!("{:?}", chain.demodulation),
        },
        sensor: SensorSize {
            lx_mm: sim.options.geometry.lx,
            ly_mm: sim.options.geometry.ly,
        },
        intrinsics: IntrinsicsRecord {
            f_mm: m.intrinsics.f,
            cx_mm: m.intrinsics.cx,
            cy_mm: m.intrinsics.cy,
            skew: m.intrinsics.skew,
        },
        distortion: m.distortion,
        gains: TrueGains {
            x1_v_per_a: sim.gain_x1,
            x2: sim.gains.x2,
            y1: sim.gains.y1,
            y2: sim.gains.y2,
        },
        images: sim
            .images
            .iter()
            .zip(&sim.poses)
            .map(|(im, p)| TruePose {
                id: im.id.clone(),
                rvec: [p.rvec.x, p.rvec.y, p.rvec.z],
                t_mm: [p.t.x, p.t.y, p.t.z],
            })
            .collect(),
    }
}
