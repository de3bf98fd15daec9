//! The page of a Monte Carlo study: what was run and what went wrong first,
//! then per study table the estimates, their bias against the truth and the
//! paper's numbers, Figure 9 as heat maps, and histograms of the estimates
//! against their truth. It takes plain data ([`StudyContent`]): the study
//! crate's results are converted by the caller, so this crate knows nothing
//! of simulation.
//!
//! Per study table, three tables of one shape (rows the quantities, columns
//! the conditions):
//! - the estimates `mean ± spread`, the spread the sample standard
//!   deviation `s` over the `n` successful trials, both rounded by the
//!   spread ([`value_with_sigma`]);
//! - the bias `mean − truth ± s/√n` (its standard error), each cell coloured
//!   by `(mean − truth)/s` (red above the truth, blue below, full colour at
//!   [`BIAS_FULL_SHADE`] spreads; white when the spread is unknown);
//! - the paper's `mean ± std` where the caller gives them.

use crate::error::ReportError;
use crate::error_map::{grid_step, heat_map_svg, HeatCell};
use crate::histogram::histogram_svg;
use crate::html::{Block, Page, Table};
use crate::number::{unit_text, value_with_digits, value_with_sigma};
use crate::plot::Frame;

/// At most this many conditions get histograms (the first ones, in table
/// order).
pub const MAX_HISTOGRAM_CONDITIONS: usize = 6;

/// A bias of this many spreads gets the full colour.
pub const BIAS_FULL_SHADE: f64 = 3.0;

/// Below this many trials per condition the page warns that the spreads
/// are rough.
pub const FEW_TRIALS: usize = 30;

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

/// A reported quantity (a row of a study table).
#[derive(Debug, Clone, PartialEq)]
pub struct StudyRow {
    /// Its name in words (`focal length f`).
    pub label: String,
    /// Its unit as written in data (`mm`, `mm^-2`; empty: none).
    pub unit: String,
    /// Whether the bias table shows it (an estimated parameter, not a
    /// residual whose truth is zero).
    pub bias: bool,
}

impl StudyRow {
    /// The heading: `focal length f (mm)`, units as printed (`mm⁻²`).
    pub fn heading(&self) -> String {
        if self.unit.is_empty() {
            self.label.clone()
        } else {
            format!("{} ({})", self.label, unit_text(&self.unit))
        }
    }
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
    /// Per row: the paper's mean and, where printed, its standard deviation.
    pub paper: Vec<Option<(f64, Option<f64>)>>,
}

/// A study table as plain data.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyTable {
    /// Title.
    pub title: String,
    /// The rows.
    pub rows: Vec<StudyRow>,
    /// Rows that get histograms, in the order they are shown.
    pub histogram_rows: Vec<usize>,
    /// The columns.
    pub columns: Vec<StudyColumn>,
    /// Remarks shown under the table (on the paper's print, on the truth).
    pub notes: Vec<String>,
}

/// A parameter offset of a Figure 9 map.
#[derive(Debug, Clone, PartialEq)]
pub struct Fig9Offset {
    /// The parameter's name in words.
    pub name: String,
    /// The offset.
    pub delta: f64,
    /// Its unit as written in data.
    pub unit: String,
}

/// One map of Figure 9 as plain data.
#[derive(Debug, Clone, PartialEq)]
pub struct Fig9Map {
    /// The lens (1 or 2).
    pub lens: u8,
    /// The condition.
    pub condition: String,
    /// The parameter offsets used.
    pub offsets: Vec<Fig9Offset>,
    /// `(x_mm, y_mm, aoa_error_deg, position_error_mm)` per grid point.
    pub grid: Vec<[f64; 4]>,
    /// Largest AoA error, degrees.
    pub max_aoa_deg: f64,
    /// Largest position error at 5 m, mm.
    pub max_position_mm: f64,
    /// Mean AoA error, degrees.
    pub mean_aoa_deg: f64,
}

/// Everything the study page shows.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyContent {
    /// Page title.
    pub title: String,
    /// A paragraph under the title: what the study is.
    pub intro: String,
    /// What was run, `(what, value)`: studies, trials, seed, version,
    /// command, …
    pub summary: Vec<(String, String)>,
    /// How to read the page: one line each (the conditions' words).
    pub reading: Vec<String>,
    /// Warnings of the caller's own, shown before those the page finds
    /// (failed trials, conditions without results, maps without points).
    pub warnings: Vec<String>,
    /// The study tables.
    pub tables: Vec<StudyTable>,
    /// The maps of Figure 9.
    pub maps: Vec<Fig9Map>,
    /// Further sections after the study tables (plain blocks).
    pub extra: Vec<Block>,
}

/// An estimate's cell: `mean ± spread` rounded by the spread, the mean
/// alone (five significant digits) from one trial or a zero spread.
pub fn estimate_cell(stats: Option<StudyStats>) -> String {
    match stats {
        None => "–".into(),
        Some(s) if s.n > 1 && s.std > 0.0 => value_with_sigma(s.mean, Some(s.std), ""),
        Some(s) => value_with_sigma(s.mean, None, ""),
    }
}

/// A bias cell: `mean − truth ± s/√n` with its sign, and its shade
/// `(mean − truth)/s / BIAS_FULL_SHADE` clamped to [−1, 1] (`None` without
/// a spread); `–` without statistics or truth.
pub fn bias_cell(stats: Option<StudyStats>, truth: Option<f64>) -> (String, Option<f64>) {
    let (Some(s), Some(t)) = (stats, truth) else {
        return ("–".into(), None);
    };
    let bias = s.mean - t;
    let spread = (s.n > 1 && s.std > 0.0).then_some(s.std);
    let error = spread.map(|sd| sd / (s.n as f64).sqrt());
    let text = value_with_sigma(bias, error, "");
    let text = if bias > 0.0 { format!("+{text}") } else { text };
    let shade = spread.map(|sd| (bias / sd / BIAS_FULL_SHADE).clamp(-1.0, 1.0));
    (text, shade)
}

/// A cell of the paper's numbers: `mean ± std` rounded by the std, or the
/// mean alone.
pub fn paper_cell(paper: Option<(f64, Option<f64>)>) -> String {
    paper.map_or("–".into(), |(m, s)| value_with_sigma(m, s, ""))
}

/// The true values of a row over the columns, each once, in order.
fn truths(table: &StudyTable, r: usize) -> String {
    let mut seen: Vec<f64> = Vec::new();
    for c in &table.columns {
        if let Some(v) = c.ideal.get(r).copied().flatten() {
            if !seen.contains(&v) {
                seen.push(v);
            }
        }
    }
    if seen.is_empty() {
        return "–".into();
    }
    seen.iter()
        .map(|v| value_with_digits(*v, 4, ""))
        .collect::<Vec<_>>()
        .join(" or ")
}

fn headers(table: &StudyTable, truth: bool) -> Vec<String> {
    let mut h = vec!["quantity".to_string()];
    if truth {
        h.push("true value".into());
    }
    h.extend(table.columns.iter().map(|c| c.label.clone()));
    h
}

/// The estimates of a study table: `mean ± spread` per condition.
pub fn study_table(table: &StudyTable) -> Table {
    let trials = table.columns.first().map_or(0, |c| c.trials);
    Table {
        caption: format!(
            "Estimates: mean ± spread (standard deviation) over the successful trials of \
             {trials} per condition"
        ),
        headers: headers(table, true),
        rows: table
            .rows
            .iter()
            .enumerate()
            .map(|(r, row)| {
                let mut cells = vec![row.heading(), truths(table, r)];
                cells.extend(
                    table
                        .columns
                        .iter()
                        .map(|c| estimate_cell(c.stats.get(r).copied().flatten())),
                );
                cells
            })
            .collect(),
    }
}

/// The bias of a study table against the truth, with its shades.
pub fn bias_table(table: &StudyTable) -> (Table, Vec<Vec<Option<f64>>>) {
    let mut rows = Vec::new();
    let mut shades = Vec::new();
    for (r, row) in table.rows.iter().enumerate() {
        if !row.bias
            || table
                .columns
                .iter()
                .all(|c| c.ideal.get(r).copied().flatten().is_none())
        {
            continue;
        }
        let mut cells = vec![row.heading()];
        let mut shade = vec![None];
        for c in &table.columns {
            let (text, s) = bias_cell(
                c.stats.get(r).copied().flatten(),
                c.ideal.get(r).copied().flatten(),
            );
            cells.push(text);
            shade.push(s);
        }
        rows.push(cells);
        shades.push(shade);
    }
    let table = Table {
        caption: format!(
            "Bias: mean − true value ± its standard error (spread/√trials). Red: above the \
             truth, blue: below; the deeper the colour, the larger the bias against the \
             spread (full at {BIAS_FULL_SHADE} spreads)"
        ),
        headers: headers(table, false),
        rows,
    };
    (table, shades)
}

/// The paper's numbers of a study table, if any column carries them.
pub fn paper_table(table: &StudyTable) -> Option<Table> {
    if table
        .columns
        .iter()
        .all(|c| c.paper.iter().all(Option::is_none))
    {
        return None;
    }
    Some(Table {
        caption: "The paper's numbers, as printed (mean ± standard deviation where it gives one)"
            .into(),
        headers: headers(table, false),
        rows: table
            .rows
            .iter()
            .enumerate()
            .map(|(r, row)| {
                let mut cells = vec![row.heading()];
                cells.extend(
                    table
                        .columns
                        .iter()
                        .map(|c| paper_cell(c.paper.get(r).copied().flatten())),
                );
                cells
            })
            .collect(),
    })
}

/// The warnings of a study: the caller's, then per condition its failed
/// trials with their reasons (or that it gave no result at all), maps
/// without points, and too few trials for a trustworthy spread.
pub fn study_warnings(content: &StudyContent) -> Vec<String> {
    let mut out = content.warnings.clone();
    for t in &content.tables {
        for c in t.columns.iter().filter(|c| c.failures > 0) {
            let reasons = if c.failure_reasons.is_empty() {
                String::new()
            } else {
                format!(": {}", c.failure_reasons.join("; "))
            };
            if c.failures >= c.trials {
                out.push(format!(
                    "{} — {}: no result, all {} trials failed{reasons}",
                    t.title, c.label, c.trials
                ));
            } else {
                out.push(format!(
                    "{} — {}: {} of {} trials failed{reasons}",
                    t.title, c.label, c.failures, c.trials
                ));
            }
        }
    }
    for m in content.maps.iter().filter(|m| m.grid.is_empty()) {
        out.push(format!(
            "Figure 9, lens {}, {}: no point of the sensor gave a ray; the map is left out",
            m.lens, m.condition
        ));
    }
    let trials = content
        .tables
        .iter()
        .flat_map(|t| t.columns.iter().map(|c| c.trials))
        .min();
    if let Some(n) = trials.filter(|n| *n < FEW_TRIALS) {
        out.push(format!(
            "Only {n} trials per condition: means and spreads are rough (the paper used 200)"
        ));
    }
    out
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

/// The Figure 9 section: a summary table, then per map its AoA and its
/// position error heat maps.
fn figure9(page: &mut Page, maps: &[Fig9Map]) -> Result<(), ReportError> {
    page.push(Block::Heading(
        "Figure 9: angle and position errors across the sensor".into(),
    ));
    page.push(Block::Paragraph(
        "For each condition of Tables 9–10 the parameters are set off their true values by \
         |bias| + 2 spreads (all in one direction, so that their effects add), and at each \
         point of the sensor the ray of the offset model is compared with the true one: the \
         angle-of-arrival (AoA) error is the angle between them, the position error their \
         distance on a plane 5 m away. Each map has its own colour scale."
            .into(),
    ));
    let three = |v: f64| value_with_digits(v, 3, "");
    page.push(Block::Table(Table {
        caption: "Figure 9 in numbers".into(),
        headers: [
            "condition",
            "largest AoA error (deg)",
            "mean AoA error (deg)",
            "largest position error at 5 m (mm)",
        ]
        .map(String::from)
        .to_vec(),
        rows: maps
            .iter()
            .map(|m| {
                vec![
                    format!("lens {}, {}", m.lens, m.condition),
                    three(m.max_aoa_deg),
                    three(m.mean_aoa_deg),
                    three(m.max_position_mm),
                ]
            })
            .collect(),
    }));
    for m in maps {
        let cells = fig9_cells(m, false);
        if cells.is_empty() {
            continue;
        }
        let step = (
            grid_step(cells.iter().map(|c| c.x)),
            grid_step(cells.iter().map(|c| c.y)),
        );
        let name = format!("lens {}, {}", m.lens, m.condition);
        let frame = |what: &str| {
            Frame::fit(
                &format!("{what}: {name}"),
                "x on the sensor (mm)",
                "y on the sensor (mm)",
                cells.iter().map(|c| (c.x, c.y)),
            )
        };
        let aoa = heat_map_svg(&cells, step, &frame("AoA error"), "AoA error (deg)")?;
        let pos = heat_map_svg(
            &fig9_cells(m, true),
            step,
            &frame("Position error at 5 m"),
            "position error (mm)",
        )?;
        let offsets: Vec<String> = m
            .offsets
            .iter()
            .map(|o| {
                let v = value_with_digits(o.delta, 2, &o.unit);
                format!("{} {}{v}", o.name, if o.delta >= 0.0 { "+" } else { "" })
            })
            .collect();
        page.push(Block::Figures(vec![
            (
                aoa,
                format!(
                    "AoA error, {name}: largest {}, mean {}. Parameters off by {}.",
                    value_with_digits(m.max_aoa_deg, 2, "deg"),
                    value_with_digits(m.mean_aoa_deg, 2, "deg"),
                    offsets.join(", ")
                ),
            ),
            (
                pos,
                format!(
                    "Position error on a plane 5 m away, {name}: largest {}.",
                    value_with_digits(m.max_position_mm, 2, "mm")
                ),
            ),
        ]));
    }
    Ok(())
}

/// Bins of a histogram of `n` values: about √n, 5 to 20.
fn bins(n: usize) -> usize {
    ((n as f64).sqrt().ceil() as usize).clamp(5, 20)
}

/// The histograms: per condition (up to [`MAX_HISTOGRAM_CONDITIONS`], each
/// label once) one per histogram row, with its true value.
fn histograms(page: &mut Page, tables: &[StudyTable]) -> Result<(), ReportError> {
    let mut seen: Vec<&str> = Vec::new();
    let mut first = true;
    for t in tables {
        for c in &t.columns {
            if seen.len() >= MAX_HISTOGRAM_CONDITIONS || seen.contains(&c.label.as_str()) {
                continue;
            }
            let mut figures = Vec::new();
            for &r in &t.histogram_rows {
                let Some(row) = t.rows.get(r) else {
                    continue;
                };
                let Some(values) = c.values.get(r).filter(|v| !v.is_empty()) else {
                    continue;
                };
                let truth = c.ideal.get(r).copied().flatten();
                let svg =
                    histogram_svg(values, truth, bins(values.len()), &c.label, &row.heading())?;
                figures.push((
                    svg,
                    format!(
                        "{}: {} successful trials{}",
                        row.label,
                        values.len(),
                        if truth.is_some() {
                            "; red line: the true value"
                        } else {
                            ""
                        }
                    ),
                ));
            }
            if figures.is_empty() {
                continue;
            }
            if first {
                page.push(Block::Heading("The estimates trial by trial".into()));
                page.push(Block::Paragraph(format!(
                    "Histograms of the estimates over the successful trials, against the true \
                     value (red line), for the first {MAX_HISTOGRAM_CONDITIONS} conditions at \
                     most."
                )));
                first = false;
            }
            seen.push(&c.label);
            page.push(Block::Paragraph(format!("{} — {}", t.title, c.label)));
            page.push(Block::Figures(figures));
        }
    }
    Ok(())
}

/// The study page: the intro, warnings, what was run and how to read it,
/// then per study table its estimates, bias and the paper's numbers, the
/// caller's further sections, Figure 9 and the histograms.
pub fn study_page(content: &StudyContent) -> Result<Page, ReportError> {
    let mut page = Page::new(&content.title);
    page.push(Block::Paragraph(content.intro.clone()));
    page.push(Block::Heading("Warnings".into()));
    let warnings = study_warnings(content);
    if warnings.is_empty() {
        page.push(Block::Paragraph(
            "None: every trial of every condition succeeded.".into(),
        ));
    } else {
        page.push(Block::List(warnings));
    }
    page.push(Block::Heading("What was run".into()));
    page.push(Block::List(
        content
            .summary
            .iter()
            .map(|(k, v)| format!("{k}: {v}"))
            .collect(),
    ));
    if !content.reading.is_empty() {
        page.push(Block::Paragraph("How to read the tables:".into()));
        page.push(Block::List(content.reading.clone()));
    }
    for t in &content.tables {
        page.push(Block::Heading(t.title.clone()));
        page.push(Block::Table(study_table(t)));
        let (table, shades) = bias_table(t);
        if !table.rows.is_empty() {
            page.push(Block::Shaded { table, shades });
        }
        if let Some(p) = paper_table(t) {
            page.push(Block::Table(p));
        }
        if !t.notes.is_empty() {
            page.push(Block::List(t.notes.clone()));
        }
    }
    for b in &content.extra {
        page.push(b.clone());
    }
    if !content.maps.is_empty() {
        figure9(&mut page, &content.maps)?;
    }
    histograms(&mut page, &content.tables)?;
    Ok(page)
}
