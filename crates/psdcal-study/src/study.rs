//! Monte Carlo studies of the calibration (the paper's Section 4): each
//! condition (lens, SNR, gain imbalance, PSD distortion, corrections) is
//! simulated and calibrated over seeded trials, and the mean and standard
//! deviation of `Cx, Cy, f, k1, k2`, the residual and the iterations are
//! reported, as in the paper's Tables 3–10; Tables 1–2 report the closed-form
//! (first-stage) `Cx, Cy, f` with and without preliminary correction and data
//! normalisation.
//!
//! *Determinism.* Trial `t` of a condition draws everything from
//! `ChaCha8Rng::seed_from_u64(mix(seed, data_key, t))`, where `data_key`
//! hashes only what generates the data (lens, SNR, imbalance, PSD
//! distortion, images, template): conditions that differ only in how they
//! calibrate (with or without corrections) see the same data sets, and the
//! results do not depend on the number of threads (trials run in parallel,
//! their results are collected in order and reduced sequentially).
//!
//! *Statistics.* Mean and sample standard deviation (n − 1) over the trials
//! whose calibration succeeded; failures are counted and their first reasons
//! kept.

use std::sync::atomic::{AtomicBool, Ordering};

use psdcal_calib::{calibrate, initialize, CalibrateOptions, InitOptions, Preliminary};
use psdcal_model::ChannelGains;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use psdcal_sim::{simulate, SignalChain, SimError, SimulationOptions, TemplateKind};

use crate::data::SimulationData;
pub use crate::tables::{table_spec, Condition, Method, Quantity, TableSpec, TABLE_IDS};

/// Options of a study.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyOptions {
    /// Trials per condition.
    pub trials: usize,
    /// The study's seed.
    pub seed: u64,
    /// Images per trial.
    pub images: usize,
    /// The template.
    pub template: TemplateKind,
    /// The signal chain.
    pub chain: SignalChain,
}

impl Default for StudyOptions {
    /// The paper's: 200 trials of nine images.
    fn default() -> Self {
        Self {
            trials: 200,
            seed: 1,
            images: 9,
            template: TemplateKind::Scatter14,
            chain: SignalChain::default(),
        }
    }
}

/// Mean and standard deviation over trials.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stats {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one trial).
    pub std: f64,
    /// Trials it is over.
    pub n: usize,
}

impl Stats {
    /// The statistics of `values` (`None` when empty or non-finite).
    pub fn of(values: &[f64]) -> Option<Stats> {
        let n = values.len();
        if n == 0 || values.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        let var = if n > 1 {
            values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64
        } else {
            0.0
        };
        Some(Stats {
            mean,
            std: var.sqrt(),
            n,
        })
    }
}

/// The result of one trial.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrialOutcome {
    /// Values in [`Quantity::FULL`] or [`Quantity::FIRST_STAGE`] order, or
    /// why the trial failed.
    pub values: Result<Vec<f64>, String>,
}

/// One column's results.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ColumnResult {
    /// The condition.
    pub condition: Condition,
    /// Per row: statistics over the successful trials.
    pub stats: Vec<Option<Stats>>,
    /// Trials run.
    pub trials: usize,
    /// Failed trials.
    pub failures: usize,
    /// The first few failure reasons.
    pub failure_reasons: Vec<String>,
    /// Per row: the value of every successful trial (for histograms; not
    /// serialised, so study.json stays small).
    #[serde(skip)]
    pub values: Vec<Vec<f64>>,
}

/// One table's results.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TableResult {
    /// What was run.
    pub spec: TableSpec,
    /// Its rows.
    pub rows: Vec<Quantity>,
    /// Its columns.
    pub columns: Vec<ColumnResult>,
}

/// A stable hash of what generates a condition's data.
fn data_key(c: &Condition, options: &StudyOptions) -> u64 {
    let text = format!(
        "lens{}|snr{:?}|imb{}|psd{}|img{}|{}",
        c.lens.number(),
        c.snr_db.map(f64::to_bits),
        c.imbalance,
        c.psd_distortion,
        options.images,
        options.template.name()
    );
    // FNV-1a.
    text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// SplitMix64 of the seed, the condition's data key and the trial index.
fn trial_seed(seed: u64, key: u64, trial: u64) -> u64 {
    let mut z = seed ^ key.rotate_left(17) ^ trial.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Runs one trial of a condition.
pub fn run_trial(condition: &Condition, options: &StudyOptions, trial: u64) -> TrialOutcome {
    let mut rng = ChaCha8Rng::seed_from_u64(trial_seed(
        options.seed,
        data_key(condition, options),
        trial,
    ));
    let sim_options = SimulationOptions {
        lens: condition.lens,
        snr_db: condition.snr_db,
        imbalance: condition.imbalance,
        psd_distortion: condition.psd_distortion,
        images: options.images,
        template: options.template,
        chain: options.chain.clone(),
        ..SimulationOptions::default()
    };
    let values = simulate(&sim_options, &mut rng)
        .map_err(|e| e.to_string())
        .and_then(|sim| {
            let data = sim.calibration_data();
            match condition.method {
                Method::FirstStage {
                    preliminary,
                    normalize,
                } => {
                    let init = InitOptions {
                        preliminary: if preliminary {
                            Preliminary::Auto
                        } else {
                            Preliminary::Off
                        },
                        normalize,
                        ..InitOptions::default()
                    };
                    let report = initialize(&data, &init).map_err(|e| e.to_string())?.report;
                    let cf = report
                        .closed_form
                        .ok_or_else(|| "no closed form".to_string())?;
                    let f = cf.focal_length().map_err(|e| e.to_string())?;
                    Ok(vec![cf.cx, cf.cy, f])
                }
                Method::Calibrate {
                    corrections,
                    paper_start,
                    fit_gains,
                } => {
                    let options = CalibrateOptions {
                        init: InitOptions {
                            preliminary: if corrections {
                                Preliminary::Auto
                            } else {
                                Preliminary::Off
                            },
                            normalize: corrections,
                            refine_start: !paper_start,
                            ..InitOptions::default()
                        },
                        refine: psdcal_calib::RefineOptions {
                            fit_gains,
                            ..psdcal_calib::RefineOptions::default()
                        },
                        ..CalibrateOptions::default()
                    };
                    let r = calibrate(&data, &options).map_err(|e| e.to_string())?;
                    let m = &r.sensor_model();
                    let gains = r.gains.unwrap_or(ChannelGains::UNIT);
                    let aoa = sim.aoa_rms_error(m, &gains).to_degrees();
                    Ok(vec![
                        m.intrinsics.cx,
                        m.intrinsics.cy,
                        m.intrinsics.f,
                        m.distortion.k1,
                        m.distortion.k2,
                        r.statistics.residual_mm2,
                        r.refine.iterations as f64,
                        aoa,
                    ])
                }
            }
        });
    TrialOutcome { values }
}

/// Whether two conditions run the same trials (they differ at most in
/// their label).
fn same_trials(a: &Condition, b: &Condition) -> bool {
    a.lens == b.lens
        && a.snr_db.map(f64::to_bits) == b.snr_db.map(f64::to_bits)
        && a.imbalance == b.imbalance
        && a.psd_distortion == b.psd_distortion
        && a.method == b.method
}

/// The number of trials [`run_tables`] runs for `specs` (conditions repeated
/// across tables run once): what a progress bar counts to.
pub fn trial_count(specs: &[TableSpec], trials: usize) -> usize {
    distinct_conditions(specs).0.len() * trials
}

/// The distinct conditions of `specs` (those differing only in their label
/// count once) and, per table and column, the index of its condition.
fn distinct_conditions(specs: &[TableSpec]) -> (Vec<&Condition>, Vec<Vec<usize>>) {
    let mut unique: Vec<&Condition> = Vec::new();
    let column_of = specs
        .iter()
        .map(|spec| {
            spec.columns
                .iter()
                .map(|c| match unique.iter().position(|u| same_trials(u, c)) {
                    Some(k) => k,
                    None => {
                        unique.push(c);
                        unique.len() - 1
                    }
                })
                .collect()
        })
        .collect();
    (unique, column_of)
}

/// Runs tables: every distinct condition's trials in parallel on rayon's
/// current pool; `progress` is called after each trial; `cancel` stops the
/// study (the result is then [`SimError::Cancelled`]).
pub fn run_tables(
    specs: &[TableSpec],
    options: &StudyOptions,
    progress: &(dyn Fn() + Sync),
    cancel: &AtomicBool,
) -> Result<Vec<TableResult>, SimError> {
    if options.trials == 0 {
        return Err(SimError::Options(
            "the number of trials must be at least 1".into(),
        ));
    }
    // Conditions that differ only in their label (Tables 9–10 repeat columns
    // of Tables 3–8) run once.
    let (unique, column_of) = distinct_conditions(specs);
    let jobs: Vec<(usize, u64)> = (0..unique.len())
        .flat_map(|u| (0..options.trials as u64).map(move |k| (u, k)))
        .collect();
    let outcomes: Vec<Option<TrialOutcome>> = jobs
        .par_iter()
        .map(|&(u, k)| {
            if cancel.load(Ordering::Relaxed) {
                return None;
            }
            let outcome = run_trial(unique[u], options, k);
            progress();
            Some(outcome)
        })
        .collect();
    if cancel.load(Ordering::Relaxed) || outcomes.iter().any(Option::is_none) {
        return Err(SimError::Cancelled);
    }
    let outcomes: Vec<TrialOutcome> = outcomes.into_iter().flatten().collect();
    let trials_of = |u: usize| &outcomes[u * options.trials..(u + 1) * options.trials];
    Ok(specs
        .iter()
        .zip(&column_of)
        .map(|(spec, columns_of)| {
            let rows = spec.rows().to_vec();
            let columns = spec
                .columns
                .iter()
                .zip(columns_of)
                .map(|(condition, &u)| {
                    let trials = trials_of(u);
                    let ok: Vec<&Vec<f64>> = trials
                        .iter()
                        .filter_map(|t| t.values.as_ref().ok())
                        .collect();
                    let failure_reasons: Vec<String> = trials
                        .iter()
                        .filter_map(|t| t.values.as_ref().err().cloned())
                        .take(3)
                        .collect();
                    let values: Vec<Vec<f64>> = (0..rows.len())
                        .map(|r| ok.iter().map(|v| v[r]).collect())
                        .collect();
                    let stats = values.iter().map(|v| Stats::of(v.as_slice())).collect();
                    ColumnResult {
                        condition: condition.clone(),
                        stats,
                        trials: trials.len(),
                        failures: trials.len() - ok.len(),
                        failure_reasons,
                        values,
                    }
                })
                .collect();
            TableResult {
                spec: spec.clone(),
                rows,
                columns,
            }
        })
        .collect())
}
