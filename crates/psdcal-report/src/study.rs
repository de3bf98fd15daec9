//! The page of a Monte Carlo study: its tables, Figure 9 as heat maps and
//! histograms of the estimated parameters against their truth. It takes
//! plain data ([`StudyTable`], [`Fig9Map`]): the study crate's results are
//! converted by the caller, so this crate knows nothing of simulation.

use crate::error::ReportError;
use crate::error_map::{grid_step, heat_map_svg, HeatCell};
use crate::histogram::histogram_svg;
use crate::html::{Block, Page, Table};
use crate::number::num;
use crate::plot::Frame;

/// At most this many conditions get histograms (the first ones, by label).
pub const MAX_HISTOGRAM_CONDITIONS: usize = 6;

/// Bins of the study's histograms.
const BINS: usize = 20;

/// Mean and standard deviation of a quantity over trials.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StudyStats {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub std: f64,
    /// Trials it is over.
    pub n: usize,
}

/// One column (condition) of a study table.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyColumn {
    /// The column heading.
    pub label: String,
    /// Per row: the true value, if any.
    pub ideal: Vec<Option<f64>>,
    /// Per row: statistics over the successful trials.
    pub stats: Vec<Option<StudyStats>>,
    /// Trials run.
    pub trials: usize,
    /// Failed trials.
    pub failures: usize,
    /// The first few failure reasons.
    pub failure_reasons: Vec<String>,
    /// Per row: the value of every successful trial (for histograms).
    pub values: Vec<Vec<f64>>,
}

/// A study table as plain data.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyTable {
    /// Title.
    pub title: String,
    /// Row headings.
    pub rows: Vec<String>,
    /// Rows that get histograms, in the order they are shown.
    pub histogram_rows: Vec<usize>,
    /// The columns.
    pub columns: Vec<StudyColumn>,
}

/// One map of Figure 9 as plain data.
#[derive(Debug, Clone, PartialEq)]
pub struct Fig9Map {
    /// The lens (1 or 2).
    pub lens: u8,
    /// The condition.
    pub condition: String,
    /// The parameter offsets used, `(name, Δ)`.
    pub offsets: Vec<(String, f64)>,
    /// `(x_mm, y_mm, aoa_error_deg, position_error_mm)` per grid point.
    pub grid: Vec<[f64; 4]>,
    /// Largest AoA error, degrees.
    pub max_aoa_deg: f64,
    /// Largest position error at 5 m, mm.
    pub max_position_mm: f64,
    /// Mean AoA error, degrees.
    pub mean_aoa_deg: f64,
}

/// A study table as an HTML table: per condition psdcal's `mean (std)`.
pub fn study_table(table: &StudyTable) -> Table {
    let mut headers = vec![String::new(), "Ideal".to_string()];
    headers.extend(table.columns.iter().map(|c| c.label.clone()));
    let rows = table
        .rows
        .iter()
        .enumerate()
        .map(|(r, label)| {
            let ideal = table
                .columns
                .first()
                .and_then(|c| c.ideal.get(r).copied().flatten());
            let mut row = vec![label.clone(), ideal.map_or("–".into(), num)];
            row.extend(table.columns.iter().map(|c| {
                c.stats.get(r).copied().flatten().map_or("–".into(), |s| {
                    if s.n > 1 {
                        format!("{} ({})", num(s.mean), num(s.std))
                    } else {
                        num(s.mean)
                    }
                })
            }));
            row
        })
        .collect();
    let trials = table.columns.first().map_or(0, |c| c.trials);
    Table {
        caption: format!(
            "{} — psdcal mean (std) over {trials} trials per column",
            table.title
        ),
        headers,
        rows,
    }
}

/// The cells of a Figure 9 map: AoA error (deg) or position error (mm).
pub fn fig9_cells(map: &Fig9Map, position: bool) -> Vec<HeatCell> {
    map.grid
        .iter()
        .map(|g| HeatCell {
            x: g[0],
            y: g[1],
            value: if position { g[3] } else { g[2] },
        })
        .collect()
}

/// The study page: a paragraph of `intro`, every table, the Figure 9 maps
/// (AoA and position error) and histograms of f, cx, cy, k1, k2 per
/// condition (up to [`MAX_HISTOGRAM_CONDITIONS`]) with the true value.
pub fn study_page(
    title: &str,
    intro: &str,
    tables: &[StudyTable],
    maps: &[Fig9Map],
) -> Result<Page, ReportError> {
    let mut page = Page::new(title);
    page.push(Block::Paragraph(intro.to_string()));
    page.push(Block::Heading("Tables".into()));
    for t in tables {
        page.push(Block::Table(study_table(t)));
        let failed: Vec<String> = t
            .columns
            .iter()
            .filter(|c| c.failures > 0)
            .map(|c| {
                format!(
                    "{}: {} of {} trials failed (e.g. {})",
                    c.label,
                    c.failures,
                    c.trials,
                    c.failure_reasons.first().map_or("", String::as_str)
                )
            })
            .collect();
        if !failed.is_empty() {
            page.push(Block::List(failed));
        }
    }
    if !maps.is_empty() {
        page.push(Block::Heading(
            "Figure 9: AoA and position errors at 5 m".into(),
        ));
        for m in maps {
            let cells = fig9_cells(m, false);
            if cells.is_empty() {
                continue;
            }
            let step = (
                grid_step(cells.iter().map(|c| c.x)),
                grid_step(cells.iter().map(|c| c.y)),
            );
            let frame = |what: &str| {
                Frame::fit(
                    &format!("Lens {}, {}: {what}", m.lens, m.condition),
                    "x (mm)",
                    "y (mm)",
                    cells.iter().map(|c| (c.x, c.y)),
                )
            };
            let aoa = heat_map_svg(&cells, step, &frame("AoA error"), "AoA error (deg)")?;
            let pos = heat_map_svg(
                &fig9_cells(m, true),
                step,
                &frame("position error"),
                "position error (mm)",
            )?;
            let offsets: Vec<String> = m
                .offsets
                .iter()
                .map(|(n, d)| format!("Δ{n} = {}", num(*d)))
                .collect();
            page.push(Block::Figures(vec![
                (
                    aoa,
                    format!(
                        "Lens {}, {}: max AoA error {} deg, mean {} deg ({})",
                        m.lens,
                        m.condition,
                        num(m.max_aoa_deg),
                        num(m.mean_aoa_deg),
                        offsets.join(", ")
                    ),
                ),
                (
                    pos,
                    format!(
                        "Lens {}, {}: max position error at 5 m {} mm",
                        m.lens,
                        m.condition,
                        num(m.max_position_mm)
                    ),
                ),
            ]));
        }
    }
    let mut seen: Vec<&str> = Vec::new();
    let mut first = true;
    for t in tables {
        for c in &t.columns {
            if seen.len() >= MAX_HISTOGRAM_CONDITIONS || seen.contains(&c.label.as_str()) {
                continue;
            }
            let mut figures = Vec::new();
            for &r in &t.histogram_rows {
                let Some(label) = t.rows.get(r) else {
                    continue;
                };
                let Some(values) = c.values.get(r).filter(|v| !v.is_empty()) else {
                    continue;
                };
                let svg = histogram_svg(
                    values,
                    c.ideal.get(r).copied().flatten(),
                    BINS,
                    &format!("{}: {label}", c.label),
                    label,
                )?;
                figures.push((
                    svg,
                    format!("{label} over {} trials; red: the true value", values.len()),
                ));
            }
            if figures.is_empty() {
                continue;
            }
            if first {
                page.push(Block::Heading(
                    "Histograms of the estimates against the truth".into(),
                ));
                first = false;
            }
            seen.push(&c.label);
            page.push(Block::Paragraph(format!("{} ({})", c.label, t.title)));
            page.push(Block::Figures(figures));
        }
    }
    Ok(page)
}
