//! The study's results as the plain data psdcal-report draws its page from:
//! the quantities in words with their units, the paper's numbers and notes
//! beside psdcal's, what was run, how to read it, and the PSD map's
//! condition as a table.

use psdcal_report::{
    Block, Fig9Map, Fig9Offset, Page, ReportError, StudyColumn, StudyContent, StudyRow, StudyStats,
    StudyTable, Table,
};
use psdcal_study::fig9::Figure9Map;
use psdcal_study::render::{num, paper_cell};
use psdcal_study::{paper, Quantity, TableResult};

use crate::study::study_psd_map::{pooled, SeedErrors};

/// Parameters that get histograms, in the order they are shown.
const HISTOGRAM_ROWS: [Quantity; 5] = [
    Quantity::F,
    Quantity::Cx,
    Quantity::Cy,
    Quantity::K1,
    Quantity::K2,
];

/// A quantity in words, its unit (as written in data), and whether it is
/// an estimated parameter (shown in the bias table).
pub fn quantity_words(q: Quantity) -> (&'static str, &'static str, bool) {
    match q {
        Quantity::Cx => ("optical centre Cx", "mm", true),
        Quantity::Cy => ("optical centre Cy", "mm", true),
        Quantity::F => ("focal length f", "mm", true),
        Quantity::K1 => ("radial distortion k1", "mm^-2", true),
        Quantity::K2 => ("radial distortion k2", "mm^-4", true),
        Quantity::Residual => ("residual (sum of squared errors)", "mm^2", false),
        Quantity::Iterations => ("iterations", "", false),
        Quantity::AoaRms => ("RMS angle-of-arrival error", "deg", false),
    }
}

/// A study table as plain data.
pub fn study_table(t: &TableResult) -> StudyTable {
    let mut notes: Vec<String> = t
        .spec
        .paper
        .and_then(paper::table)
        .map(|p| {
            p.notes
                .iter()
                .map(|n| format!("On the paper's print: {n}"))
                .collect()
        })
        .unwrap_or_default();
    if t.columns.iter().any(|c| c.condition.psd_distortion) && t.rows.contains(&Quantity::K1) {
        notes.push(
            "With the PSD's distortion the true k1 is the lens's k1 plus the PSD's l1 (a radial \
             fit cannot tell them apart): hence two true values of k1."
                .into(),
        );
    }
    StudyTable {
        title: t.spec.title.clone(),
        rows: t
            .rows
            .iter()
            .map(|q| {
                let (label, unit, bias) = quantity_words(*q);
                StudyRow {
                    label: label.into(),
                    unit: unit.into(),
                    bias,
                }
            })
            .collect(),
        histogram_rows: HISTOGRAM_ROWS
            .iter()
            .filter_map(|q| t.rows.iter().position(|x| x == q))
            .collect(),
        columns: t
            .columns
            .iter()
            .enumerate()
            .map(|(k, c)| StudyColumn {
                label: c.condition.label.clone(),
                ideal: t.rows.iter().map(|q| c.condition.ideal(*q)).collect(),
                stats: c
                    .stats
                    .iter()
                    .map(|s| {
                        s.map(|s| StudyStats {
                            mean: s.mean,
                            std: s.std,
                            n: s.n,
                        })
                    })
                    .collect(),
                trials: c.trials,
                failures: c.failures,
                failure_reasons: c.failure_reasons.clone(),
                values: c.values.clone(),
                paper: t.rows.iter().map(|q| paper_cell(t, k, *q)).collect(),
            })
            .collect(),
        notes,
    }
}

/// A Figure 9 map as plain data, its offsets named in words.
pub fn fig9_map(m: &Figure9Map) -> Fig9Map {
    let words = |name: &str| match name {
        "cx" => quantity_words(Quantity::Cx),
        "cy" => quantity_words(Quantity::Cy),
        "f" => quantity_words(Quantity::F),
        "k1" => quantity_words(Quantity::K1),
        "k2" => quantity_words(Quantity::K2),
        _ => ("", "", false),
    };
    Fig9Map {
        lens: m.lens,
        condition: m.condition.clone(),
        offsets: m
            .offsets
            .iter()
            .map(|(name, delta)| {
                let (label, unit, _) = words(name);
                Fig9Offset {
                    name: if label.is_empty() {
                        name.clone()
                    } else {
                        label.into()
                    },
                    delta: *delta,
                    unit: unit.into(),
                }
            })
            .collect(),
        grid: m.grid.clone(),
        max_aoa_deg: m.max_aoa_deg,
        max_position_mm: m.max_position_mm,
        mean_aoa_deg: m.mean_aoa_deg,
    }
}

/// The PSD map's condition as a section of the page: the pooled RMS angle
/// errors of the four calibrations and their ratios, and the seeds a
/// calibration refused, `(seed, reason)`.
pub fn psd_map_blocks(seeds: &[SeedErrors], refused: &[(u64, String)]) -> Vec<Block> {
    let (map, refined, l1, clean) = (
        pooled(seeds, |e| e.map),
        pooled(seeds, |e| e.refined),
        pooled(seeds, |e| e.l1),
        pooled(seeds, |e| e.clean),
    );
    let worst = seeds.iter().map(|e| e.map_error_mm).fold(0.0, f64::max);
    let noise = seeds
        .iter()
        .map(|e| e.scan_noise_mm)
        .fold(f64::INFINITY, f64::min);
    let mut blocks = vec![
        Block::Heading(format!(
            "The PSD's non-radial non-linearity: lens 2, 40 dB, 12 images, {} seeds",
            seeds.len() + refused.len()
        )),
        Block::Table(Table {
            caption: "RMS angle error over 9 × 9 held-out directions, pooled over the seeds".into(),
            headers: [
                "calibration",
                "RMS angle error (µrad)",
                "ratio to no non-linearity",
            ]
            .map(String::from)
            .to_vec(),
            rows: [
                ("with the map from a 0.25 mm scan, held fixed", map),
                ("with the same map refined, its scan as the prior", refined),
                ("with l1 freed instead", l1),
                ("without non-linearity (same poses and noise)", clean),
            ]
            .iter()
            .map(|(name, v)| vec![name.to_string(), num(1e6 * v), num(v / clean)])
            .collect(),
        }),
        Block::Paragraph(format!(
            "The map's error against the true field: at most {} µm; the scan's own noise: at \
             least {} µm.",
            num(1e3 * worst),
            num(1e3 * noise)
        )),
    ];
    if !refused.is_empty() {
        blocks.push(Block::Paragraph(format!(
            "Seeds refused by a calibration (left out of the pooled errors): {}.",
            refused
                .iter()
                .map(|(seed, reason)| format!("{seed} ({reason})"))
                .collect::<Vec<_>>()
                .join("; ")
        )));
    }
    blocks
}

/// The PSD map's condition: the seeds that ran and those a calibration
/// refused, `(seed, reason)`.
#[derive(Debug, Clone, Copy)]
pub struct PsdMapSeeds<'a> {
    /// The seeds that ran.
    pub seeds: &'a [SeedErrors],
    /// The seeds refused.
    pub refused: &'a [(u64, String)],
}

/// What the page says about a run besides its results.
pub struct StudyRun<'a> {
    /// What was run, `(what, value)`.
    pub summary: Vec<(String, String)>,
    /// The PSD map's condition, if run.
    pub psd_map: Option<PsdMapSeeds<'a>>,
    /// The folder of study.md, study.csv and study.json.
    pub out: &'a std::path::Path,
}

/// The study page.
pub fn study_page(
    run: &StudyRun<'_>,
    tables: &[TableResult],
    maps: &[Figure9Map],
) -> Result<Page, ReportError> {
    let content = StudyContent {
        title: "psdcal study: the paper's Monte Carlo trials".into(),
        intro: format!(
            "Each condition of the paper's simulation (lens, noise, gain imbalance, the PSD's \
             distortion, corrections) is simulated and calibrated over seeded trials; the \
             estimates are compared with the true values and with the paper's numbers. The \
             same numbers are in {0}/study.md, {0}/study.csv and {0}/study.json.",
            run.out.display()
        ),
        summary: run.summary.clone(),
        reading: vec![
            "Conditions: 30, 40, 50 dB is each electrode channel's signal-to-noise ratio (no \
             noise: none added); imbalance: unequal amplifier gains; PSD: the sensor's own \
             pin-cushion distortion; corrections: the preliminary distortion correction and the \
             data normalisation; self-calibration: the amplifier gains are fitted too."
                .into(),
            "Spread: the standard deviation over the trials, the scatter one calibration \
             shows. The bias's ± is its standard error, which shrinks with more trials."
                .into(),
        ],
        warnings: Vec::new(),
        tables: tables.iter().map(study_table).collect(),
        maps: maps.iter().map(fig9_map).collect(),
        extra: run
            .psd_map
            .map(|m| psd_map_blocks(m.seeds, m.refused))
            .unwrap_or_default(),
    };
    psdcal_report::study_page(&content)
}
