//! The paper's Monte Carlo evaluation from one request: the rules that
//! choose the tables, the checks before any work, the run (progress and
//! cancellation through a callback and a flag), and the files (study.md,
//! study.csv, study.json, fig9_*.csv and, if asked for, study.html), each
//! written atomically after the whole study succeeded.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use psdcal_io::{write_atomic, write_atomic_bytes, OutputFolder};
use psdcal_model::PsdGeometry;
use psdcal_study::fig9::{figure9, Figure9Map};
use psdcal_study::render::{csv_rows, markdown, num, CSV_HEADER};
use psdcal_study::{run_tables, table_spec, StudyOptions, TableResult, TableSpec, TABLE_IDS};

use crate::base::error::{Error, Result};
use crate::base::provenance::utc_iso8601;
use crate::simulation::simulate::{chain_with_record, record_cycles_flag};
use crate::study::study_page::{study_page, PsdMapSeeds, StudyRun};
use crate::study::study_psd_map::{pooled, psd_map_seed, SeedErrors};

/// The PSD-map condition's seeds: those that ran and those refused (a
/// calibration of the seed refused its data: seed, message).
#[derive(Debug, Clone, Default)]
struct PsdMapRun {
    seeds: Vec<SeedErrors>,
    failures: Vec<(u64, String)>,
}

/// The PSD-map condition's section of study.md: the pooled RMS angle
/// errors (µrad) of the four calibrations, their ratios, the map's own
/// error next to the scan's noise, and the refused seeds.
fn psd_map_markdown(run: &PsdMapRun) -> String {
    let seeds = &run.seeds;
    let mut out = String::new();
    let failed = run.failures.len();
    if seeds.is_empty() {
        let _ = writeln!(
            out,
            "### The PSD's non-radial non-linearity\n\nEvery seed was refused ({failed}).\n"
        );
        return out;
    }
    let (map, l1, clean) = (
        pooled(seeds, |e| e.map),
        pooled(seeds, |e| e.l1),
        pooled(seeds, |e| e.clean),
    );
    let _ = writeln!(
        out,
        "### The PSD's non-radial non-linearity: lens 2, 40 dB, 12 images, {} seeds\n",
        seeds.len() + failed
    );
    let _ = writeln!(
        out,
        "RMS angle error over 9 × 9 held-out directions, pooled over the seeds.\n"
    );
    let _ = writeln!(
        out,
        "| condition | RMS angle error (µrad) | ratio to no non-linearity |"
    );
    let _ = writeln!(out, "|---|---|---|");
    for (name, v) in [
        ("map from a 0.25 mm scan, held fixed", map),
        (
            "the same map refined (--refine-psd-map)",
            pooled(seeds, |e| e.refined),
        ),
        ("l1 freed instead", l1),
        ("no non-linearity (same poses and noise)", clean),
    ] {
        let _ = writeln!(out, "| {name} | {} | {} |", num(1e6 * v), num(v / clean));
    }
    let worst = seeds.iter().map(|e| e.map_error_mm).fold(0.0, f64::max);
    let _ = writeln!(
        out,
        "\nThe map's RMS error against the true field, pooled: {} µm held, {} µm refined.",
        num(1e3 * pooled(seeds, |e| e.map_error_mm)),
        num(1e3 * pooled(seeds, |e| e.refined_map_error_mm))
    );
    let noise = seeds
        .iter()
        .map(|e| e.scan_noise_mm)
        .fold(f64::INFINITY, f64::min);
    let _ = writeln!(
        out,
        "\nMap / l1 freed: {}. The map's error against the true field: at most {} µm, the \
         scan's own noise at least {} µm.\n",
        num(map / l1),
        num(1e3 * worst),
        num(1e3 * noise)
    );
    if failed > 0 {
        let _ = writeln!(
            out,
            "{failed} of {} seeds were refused by a calibration and are not pooled:\n",
            seeds.len() + failed
        );
        for (seed, message) in &run.failures {
            let _ = writeln!(out, "- seed {seed}: {message}");
        }
        out.push('\n');
    }
    out
}

/// The PSD-map condition in study.json.
fn psd_map_json(run: &PsdMapRun) -> serde_json::Value {
    let seeds = &run.seeds;
    let pool = |f: fn(&SeedErrors) -> f64| (!seeds.is_empty()).then(|| pooled(seeds, f));
    serde_json::json!({
        "seeds": seeds,
        "pooled_map_rad": pool(|e| e.map),
        "pooled_refined_rad": pool(|e| e.refined),
        "pooled_l1_rad": pool(|e| e.l1),
        "pooled_clean_rad": pool(|e| e.clean),
        "failures": run.failures.iter().map(|(seed, message)| serde_json::json!({"seed": seed, "error": message})).collect::<Vec<_>>(),
    })
}

/// The study id of the PSD-map condition (`crate::study::study_psd_map`): run
/// only when named (not part of `all`).
pub const PSD_MAP_STUDY: &str = "psdmap";

/// Whether `id` names something `study` runs: `table1` … `table10`, `fig9`,
/// `psdmap` or `all`.
/// Every id `study` accepts, in the order the command line lists them.
pub fn study_ids() -> Vec<&'static str> {
    let mut ids = TABLE_IDS.to_vec();
    ids.extend(["fig9", PSD_MAP_STUDY, "all"]);
    ids
}

/// `study TABLE`: a study id (any case), refused with the accepted ids.
pub fn parse_study_id(text: &str) -> std::result::Result<String, String> {
    let id = text.trim().to_ascii_lowercase();
    if is_study_id(&id) {
        Ok(id)
    } else {
        Err(format!(
            "unknown value '{text}'; expected one of {}",
            study_ids().join(", ")
        ))
    }
}

/// Whether `id` is one of [`study_ids`].
pub fn is_study_id(id: &str) -> bool {
    id == "all" || id == "fig9" || id == PSD_MAP_STUDY || TABLE_IDS.contains(&id)
}

/// The tables asked for: `all` expands to every table and `fig9`,
/// duplicates go, the paper's order (`fig9` last).
pub fn expand_tables(ids: &[String]) -> Vec<String> {
    let mut wanted: Vec<String> = Vec::new();
    for t in ids {
        if t == "all" {
            wanted.extend(TABLE_IDS.iter().map(|s| s.to_string()));
            wanted.push("fig9".into());
        } else {
            wanted.push(t.clone());
        }
    }
    let order = |t: &String| {
        TABLE_IDS
            .iter()
            .position(|x| x == t)
            .unwrap_or(TABLE_IDS.len())
    };
    wanted.sort_by_key(order);
    wanted.dedup();
    wanted
}

/// What to run.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyRequest {
    /// Table ids in order, each once (`fig9` last when asked for).
    pub tables: Vec<String>,
    /// Trials per condition.
    pub trials: usize,
    /// Worker threads (default: every core).
    pub threads: Option<usize>,
    /// The study's seed.
    pub seed: u64,
    /// Record length of the signal chain, cycles.
    pub record_cycles: usize,
    /// Output folder.
    pub out: PathBuf,
    /// Folder of study.html, if asked for.
    pub report: Option<PathBuf>,
    /// Replace files in `out` (and `report`) that psdcal did not write
    /// there (docs/formats.md, "Output folders").
    pub force: bool,
}

/// A checked study, ready to run.
#[derive(Debug, Clone)]
pub struct StudyPlan {
    request: StudyRequest,
    specs: Vec<TableSpec>,
    want_fig9: bool,
    want_psd_map: bool,
    options: StudyOptions,
}

/// What a study wrote.
#[derive(Debug, Clone)]
pub struct StudyOutcome {
    /// study.md's text.
    pub markdown: String,
    /// study.json's content.
    pub json: serde_json::Value,
    /// study.html, if written.
    pub page: Option<PathBuf>,
}

impl StudyOutcome {
    /// The summary of a study written into the folder `out`.
    pub fn summary(&self, out: &std::path::Path) -> crate::base::summary::Summary {
        let text = format!(
            "{}wrote {1}/study.md, {1}/study.csv, {1}/study.json",
            self.markdown,
            out.display()
        );
        crate::base::summary::Summary::new(text, self.json.clone()).wrote(self.page.as_deref())
    }
}

/// Checks everything before the work starts: the tables, the signal chain,
/// that the output folders can be written.
pub fn plan_study(request: &StudyRequest) -> Result<StudyPlan> {
    let want_fig9 = request.tables.iter().any(|t| t == "fig9");
    let mut ids: Vec<String> = request
        .tables
        .iter()
        .filter(|t| *t != "fig9" && *t != PSD_MAP_STUDY)
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
        .map(|id| table_spec(id).ok_or_else(|| Error::Options(format!("unknown table '{id}'"))))
        .collect::<Result<_>>()?;
    check_output_folder(&request.out)?;
    // Checked again, with the Figure 9 files, before anything is written.
    OutputFolder::claim(&request.out, &study_files(&[]), request.force)?;
    if let Some(dir) = &request.report {
        check_output_folder(dir)?;
        OutputFolder::claim(dir, &[STUDY_PAGE.to_string()], request.force)?;
    }
    let options = StudyOptions {
        trials: request.trials,
        seed: request.seed,
        chain: chain_with_record(request.record_cycles)?,
        ..StudyOptions::default()
    };
    Ok(StudyPlan {
        request: request.clone(),
        specs,
        want_fig9,
        want_psd_map: request.tables.iter().any(|t| t == PSD_MAP_STUDY),
        options,
    })
}

/// The study's page in its report folder.
const STUDY_PAGE: &str = "study.html";

/// The files a study writes into its folder: the tables and one file per
/// Figure 9 map.
fn study_files(maps: &[Figure9Map]) -> Vec<String> {
    let tables = ["study.md", "study.csv", "study.json"].map(String::from);
    let fig9 = maps
        .iter()
        .enumerate()
        .map(|(k, m)| format!("fig9_lens{}_{}.csv", m.lens, k + 1));
    tables.into_iter().chain(fig9).collect()
}

/// Creates the folder and proves it can be written, before any work.
fn check_output_folder(dir: &Path) -> Result<()> {
    let folder = |message: String| Error::OutputFolder {
        path: dir.to_path_buf(),
        message,
    };
    std::fs::create_dir_all(dir).map_err(|e| {
        folder(format!(
            "cannot create the output folder {}: {e}",
            dir.display()
        ))
    })?;
    let probe = dir.join(".psdcal-write-test");
    write_atomic_bytes(&probe, b"").map_err(|e| {
        folder(format!(
            "the output folder {} cannot be written: {e}",
            dir.display()
        ))
    })?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

impl StudyPlan {
    /// Trials to run in all.
    pub fn trial_count(&self) -> u64 {
        (psdcal_study::study::trial_count(&self.specs, self.request.trials)
            + if self.want_psd_map {
                self.request.trials
            } else {
                0
            }) as u64
    }

    /// Runs the study on the current rayon pool (`tick` after each trial;
    /// `cancel` stops it and nothing is written) and writes the files.
    pub fn run(&self, tick: &(dyn Fn() + Sync), cancel: &AtomicBool) -> Result<StudyOutcome> {
        let mut pool = rayon::ThreadPoolBuilder::new();
        if let Some(n) = self.request.threads {
            pool = pool.num_threads(n);
        }
        let pool = pool
            .build()
            .map_err(|e| Error::Options(format!("cannot start the worker threads: {e}")))?;
        let started = Instant::now();
        let result = pool.install(|| run_tables(&self.specs, &self.options, &tick, cancel));
        let tables = match result {
            Err(psdcal_sim::SimError::Cancelled) => return Err(Error::Interrupted),
            other => other?,
        };
        let psd_map = if self.want_psd_map {
            Some(pool.install(|| self.run_psd_map(tick, cancel))?)
        } else {
            None
        };
        let elapsed = started.elapsed().as_secs_f64();
        let maps = if self.want_fig9 {
            figure9(&tables, &PsdGeometry::default())
        } else {
            Vec::new()
        };
        self.write(&tables, &maps, psd_map.as_ref(), elapsed)
    }

    /// The PSD-map condition: one seed per trial (`seed + k`), in memory. A
    /// seed whose calibration is refused is counted, not pooled.
    fn run_psd_map(&self, tick: &(dyn Fn() + Sync), cancel: &AtomicBool) -> Result<PsdMapRun> {
        use rayon::prelude::*;
        use std::sync::atomic::Ordering;
        let result: Result<Vec<std::result::Result<SeedErrors, (u64, String)>>> =
            (0..self.request.trials)
                .into_par_iter()
                .map(|k| {
                    if cancel.load(Ordering::Relaxed) {
                        return Err(Error::Interrupted);
                    }
                    let seed = self.request.seed + k as u64;
                    let e = psd_map_seed(seed, false);
                    tick();
                    match e {
                        Ok(e) => Ok(Ok(e)),
                        Err(e @ Error::Interrupted) => Err(e),
                        Err(e) => Ok(Err((seed, e.to_string()))),
                    }
                })
                .collect();
        let mut run = PsdMapRun::default();
        for r in result? {
            match r {
                Ok(e) => run.seeds.push(e),
                Err(f) => run.failures.push(f),
            }
        }
        Ok(run)
    }

    fn write(
        &self,
        tables: &[TableResult],
        maps: &[Figure9Map],
        psd_map: Option<&PsdMapRun>,
        elapsed: f64,
    ) -> Result<StudyOutcome> {
        let r = &self.request;
        let mut report = self.markdown(tables, maps, elapsed);
        if let Some(seeds) = psd_map {
            report.push_str(&psd_map_markdown(seeds));
        }
        let folder = OutputFolder::claim(&r.out, &study_files(maps), r.force)?;
        let page_folder = match &r.report {
            Some(dir) => Some(OutputFolder::claim(
                dir,
                &[STUDY_PAGE.to_string()],
                r.force,
            )?),
            None => None,
        };
        write_atomic_bytes(r.out.join("study.md"), report.as_bytes())?;
        write_atomic(r.out.join("study.csv"), |w| {
            writeln!(w, "{CSV_HEADER}")?;
            for t in tables {
                w.write_all(csv_rows(t).as_bytes())?;
            }
            Ok(())
        })?;
        let json = serde_json::json!({
            "seed": r.seed,
            "trials": r.trials,
            "tables": tables,
            "fig9": maps.iter().map(|m| serde_json::json!({
                "lens": m.lens, "condition": m.condition, "offsets": m.offsets,
                "max_aoa_deg": m.max_aoa_deg, "mean_aoa_deg": m.mean_aoa_deg, "max_position_mm": m.max_position_mm,
            })).collect::<Vec<_>>(),
            "psd_map": psd_map.map(psd_map_json),
            "elapsed_s": elapsed,
        });
        let text = serde_json::to_string_pretty(&json)
            .map_err(|e| Error::Input(format!("cannot encode study.json: {e}")))?;
        write_atomic_bytes(r.out.join("study.json"), text.as_bytes())?;
        for (k, m) in maps.iter().enumerate() {
            write_atomic(
                r.out.join(format!("fig9_lens{}_{}.csv", m.lens, k + 1)),
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
        let page = match &r.report {
            Some(dir) => {
                let run = StudyRun {
                    summary: self.summary(tables, elapsed),
                    psd_map: psd_map.map(|r| PsdMapSeeds {
                        seeds: &r.seeds,
                        refused: &r.failures,
                    }),
                    out: &r.out,
                };
                let page = study_page(&run, tables, maps)?;
                let path = dir.join(STUDY_PAGE);
                write_atomic_bytes(&path, page.render().as_bytes())?;
                Some(path)
            }
            None => None,
        };
        folder.finish()?;
        if let Some(f) = page_folder {
            f.finish()?;
        }
        Ok(StudyOutcome {
            markdown: report,
            json,
            page,
        })
    }

    /// What was run, for the page: the studies, conditions, trials, seed,
    /// data, run time, version, command and time.
    fn summary(&self, tables: &[TableResult], elapsed: f64) -> Vec<(String, String)> {
        let r = &self.request;
        let studies: Vec<String> = r
            .tables
            .iter()
            .map(|t| match t.strip_prefix("table") {
                Some(n) => format!("Table {n}"),
                None if t == "fig9" => "Figure 9 (from Tables 9 and 10)".into(),
                None if t == PSD_MAP_STUDY => "the PSD map's condition".into(),
                None => t.clone(),
            })
            .collect();
        let columns: usize = tables.iter().map(|t| t.columns.len()).sum();
        let distinct = psdcal_study::study::trial_count(&self.specs, 1);
        let threads = r
            .threads
            .map_or("every core".to_string(), |n| format!("{n} threads"));
        [
            ("Studies", studies.join(", ")),
            (
                "Conditions",
                format!(
                    "{columns} table columns, {distinct} distinct conditions (a condition                      repeated in another table runs once)"
                ),
            ),
            ("Trials per condition", r.trials.to_string()),
            ("Trials in all", self.trial_count().to_string()),
            (
                "Data of a trial",
                format!(
                    "{} images of the {} template, {} modulation cycles per LED",
                    self.options.images,
                    self.options.template.name(),
                    r.record_cycles
                ),
            ),
            (
                "Seed",
                format!("{} (each trial its own ChaCha8 stream)", r.seed),
            ),
            ("Run time", format!("{elapsed:.1} s on {threads}")),
            ("psdcal version", env!("CARGO_PKG_VERSION").to_string()),
            ("Command", self.reproduce()),
            ("Written (UTC)", utc_iso8601(std::time::SystemTime::now())),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }

    /// The command that reproduces this study.
    fn reproduce(&self) -> String {
        let r = &self.request;
        format!(
            "psdcal study {} --trials {} --seed {}{}",
            r.tables.join(" "),
            r.trials,
            r.seed,
            record_cycles_flag(r.record_cycles)
        )
    }

    fn markdown(&self, tables: &[TableResult], maps: &[Figure9Map], elapsed: f64) -> String {
        let r = &self.request;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "## psdcal study: {} trials per condition, seed {} ({:.1} s)\n",
            r.trials, r.seed, elapsed
        );
        let _ = writeln!(out, "Reproduce with `{}`.\n", self.reproduce());
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
}
