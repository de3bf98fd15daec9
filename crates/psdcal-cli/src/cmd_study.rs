//! `psdcal study`: the paper's Monte Carlo evaluation from one command.
//!
//! Everything is checked before the work starts (tables, trials, threads,
//! that the output folder can be written); the trials run on a rayon pool of
//! the requested size behind a progress bar (on a terminal only); Ctrl-C
//! stops the study and nothing is written; the results are written
//! atomically (study.md, study.csv, study.json, and fig9_*.csv grids).

use std::fmt::Write as _;
use std::io::{IsTerminal, Write as _};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{anyhow, Context as _};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use psdcal_io::{write_atomic, write_atomic_bytes};
use psdcal_model::PsdGeometry;
use psdcal_sim::fig9::{figure9, ErrorMap};
use psdcal_sim::render::{csv_rows, markdown, num, CSV_HEADER};
use psdcal_sim::{run_tables, table_spec, SimError, StudyOptions, TableResult, TableSpec};

use crate::cli::Output;
use crate::cli_sim::StudyConfig;

/// Runs `study`.
pub fn run(config: &StudyConfig, output: Output) -> anyhow::Result<()> {
    let want_fig9 = config.tables.iter().any(|t| t == "fig9");
    let mut ids: Vec<String> = config
        .tables
        .iter()
        .filter(|t| *t != "fig9")
        .cloned()
        .collect();
    if want_fig9 {
        for t in ["table9", "table10"] {
            if !ids.iter().any(|x| x == t) {
                ids.push(t.into());
            }
        }
    }
    let specs: Vec<TableSpec> = ids
        .iter()
        .map(|id| table_spec(id).ok_or_else(|| anyhow!("unknown table '{id}'")))
        .collect::<anyhow::Result<_>>()?;
    check_output_folder(&config.out)?;
    if let Some(dir) = &config.report {
        check_output_folder(dir)?;
    }
    let options = StudyOptions {
        trials: config.trials,
        seed: config.seed,
        chain: crate::cli_sim::chain_with_record(config.record_cycles)?,
        ..StudyOptions::default()
    };
    let total = psdcal_sim::study::trial_count(&specs, config.trials) as u64;
    let bar = progress_bar(total, output);
    let cancel = Arc::new(AtomicBool::new(false));
    {
        let cancel = cancel.clone();
        // A second handler cannot be installed; without one, Ctrl-C just ends the process
        // before anything is written, which is also safe.
        let _ = ctrlc::set_handler(move || cancel.store(true, Ordering::SeqCst));
    }
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = config.threads {
        pool = pool.num_threads(n);
    }
    let pool = pool.build().context("cannot start the worker threads")?;
    let started = Instant::now();
    let tick = || bar.inc(1);
    let result = pool.install(|| run_tables(&specs, &options, &tick, &cancel));
    bar.finish_and_clear();
    let tables = match result {
        Err(SimError::Cancelled) => {
            return Err(anyhow!("the study was interrupted; nothing was written"))
        }
        other => other?,
    };
    let elapsed = started.elapsed().as_secs_f64();
    let maps = if want_fig9 {
        figure9(&tables, &PsdGeometry::default())
    } else {
        Vec::new()
    };
    let report = render_report(config, &tables, &maps, elapsed);
    write_atomic_bytes(config.out.join("study.md"), report.as_bytes())?;
    write_atomic(config.out.join("study.csv"), |w| {
        writeln!(w, "{CSV_HEADER}")?;
        for t in &tables {
            w.write_all(csv_rows(t).as_bytes())?;
        }
        Ok(())
    })?;
    let json = serde_json::json!({
        "seed": config.seed,
        "trials": config.trials,
        "tables": tables,
        "fig9": maps.iter().map(|m| serde_json::json!({
            "lens": m.lens, "condition": m.condition, "offsets": m.offsets,
            "max_aoa_deg": m.max_aoa_deg, "mean_aoa_deg": m.mean_aoa_deg, "max_position_mm": m.max_position_mm,
        })).collect::<Vec<_>>(),
        "elapsed_s": elapsed,
    });
    write_atomic_bytes(
        config.out.join("study.json"),
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    for (k, m) in maps.iter().enumerate() {
        write_atomic(
            config
                .out
                .join(format!("fig9_lens{}_{}.csv", m.lens, k + 1)),
            |w| {
                writeln!(
                    w,
                    "# Figure 9, lens {}, {}: offsets {:?}",
                    m.lens, m.condition, m.offsets
                )?;
                writeln!(w, "x_mm,y_mm,aoa_error_deg,position_error_mm")?;
                for g in &m.grid {
                    writeln!(w, "{},{},{},{}", g[0], g[1], g[2], g[3])?;
                }
                Ok(())
            },
        )?;
    }
    let page = match &config.report {
        Some(dir) => {
            let intro = format!(
                "{} trials per condition, seed {} ({:.1} s). Reproduce with: psdcal study {} --trials {} --seed {}{}",
                config.trials,
                config.seed,
                elapsed,
                config.tables.join(" "),
                config.trials,
                config.seed,
                crate::cli_sim::record_cycles_flag(config.record_cycles)
            );
            let page = psdcal_report::study_page("psdcal study", &intro, &tables, &maps)?;
            let path = dir.join("study.html");
            write_atomic_bytes(&path, page.render().as_bytes())?;
            Some(path)
        }
        None => None,
    };
    match output {
        Output::Quiet => {}
        Output::Json => println!("{}", serde_json::to_string_pretty(&json)?),
        Output::Text => {
            print!("{report}");
            println!(
                "wrote {0}/study.md, {0}/study.csv, {0}/study.json",
                config.out.display()
            );
            if let Some(path) = &page {
                println!("wrote {}", path.display());
            }
        }
    }
    Ok(())
}

/// Creates the folder and proves it can be written, before any work.
fn check_output_folder(dir: &std::path::Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)
        .map_err(|e| anyhow!("cannot create the output folder {}: {e}", dir.display()))?;
    let probe = dir.join(".psdcal-write-test");
    write_atomic_bytes(&probe, b"")
        .map_err(|e| anyhow!("the output folder {} cannot be written: {e}", dir.display()))?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

fn progress_bar(total: u64, output: Output) -> ProgressBar {
    if output != Output::Text || !std::io::stderr().is_terminal() {
        return ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
    }
    let bar = ProgressBar::new(total);
    if let Ok(style) =
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} trials, {eta} left")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

fn render_report(
    config: &StudyConfig,
    tables: &[TableResult],
    maps: &[ErrorMap],
    elapsed: f64,
) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "## psdcal study: {} trials per condition, seed {} ({:.1} s)\n",
        config.trials, config.seed, elapsed
    );
    let _ = writeln!(
        out,
        "Reproduce with `psdcal study {} --trials {} --seed {}{}`.\n",
        config.tables.join(" "),
        config.trials,
        config.seed,
        crate::cli_sim::record_cycles_flag(config.record_cycles)
    );
    for t in tables {
        out.push_str(&markdown(t));
    }
    if !maps.is_empty() {
        let _ = writeln!(out, "### Figure 9: AoA and position errors at 5 m, parameters off by |mean − ideal| + 2·std\n");
        let _ = writeln!(out, "| lens | condition | max AoA error (deg) | mean AoA error (deg) | max position error at 5 m (mm) |");
        let _ = writeln!(out, "|---|---|---|---|---|");
        for m in maps {
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} |",
                m.lens,
                m.condition,
                num(m.max_aoa_deg),
                num(m.mean_aoa_deg),
                num(m.max_position_mm)
            );
        }
        let _ = writeln!(
            out,
            "\nGrids: fig9_lens*_*.csv (x_mm, y_mm, aoa_error_deg, position_error_mm).\n"
        );
    }
    out
}
