//! The page of a Monte Carlo study: its tables, Figure 9 as heat maps and
//! histograms of the estimated parameters against their truth.

use psdcal_sim::fig9::ErrorMap;
use psdcal_sim::render::num;
use psdcal_sim::study::{Quantity, TableResult};

use crate::error::ReportError;
use crate::error_map::{grid_step, heat_map_svg, HeatCell};
use crate::histogram::histogram_svg;
use crate::html::{Block, Page, Table};
use crate::plot::Frame;

/// Parameters that get histograms.
const HISTOGRAM_ROWS: [Quantity; 5] = [
    Quantity::F,
    Quantity::Cx,
    Quantity::Cy,
    Quantity::K1,
    Quantity::K2,
];

/// At most this many conditions get histograms (the first ones, by label).
pub const MAX_HISTOGRAM_CONDITIONS: usize = 6;

/// Bins of the study's histograms.
const BINS: usize = 20;

/// A study table as an HTML table: per condition psdcal's `mean (std)`.
pub fn study_table(table: &TableResult) -> Table {
    let mut headers = vec![String::new(), "Ideal".to_string()];
    headers.extend(table.columns.iter().map(|c| c.condition.label.clone()));
    let rows = table
        .rows
        .iter()
        .enumerate()
        .map(|(r, q)| {
            let ideal = table.columns.first().and_then(|c| c.condition.ideal(*q));
            let mut row = vec![q.label().to_string(), ideal.map_or("–".into(), num)];
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
            table.spec.title
        ),
        headers,
        rows,
    }
}

/// The cells of a Figure 9 map: AoA error (deg) or position error (mm).
pub fn fig9_cells(map: &ErrorMap, position: bool) -> Vec<HeatCell> {
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
    tables: &[TableResult],
    maps: &[ErrorMap],
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
                    c.condition.label,
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
            if seen.len() >= MAX_HISTOGRAM_CONDITIONS || seen.contains(&c.condition.label.as_str())
            {
                continue;
            }
            let mut figures = Vec::new();
            for q in HISTOGRAM_ROWS {
                let Some(r) = t.rows.iter().position(|x| *x == q) else {
                    continue;
                };
                let Some(values) = c.values.get(r).filter(|v| !v.is_empty()) else {
                    continue;
                };
                let svg = histogram_svg(
                    values,
                    c.condition.ideal(q),
                    BINS,
                    &format!("{}: {}", c.condition.label, q.label()),
                    q.label(),
                )?;
                figures.push((
                    svg,
                    format!(
                        "{} over {} trials; red: the true value",
                        q.label(),
                        values.len()
                    ),
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
            seen.push(&c.condition.label);
            page.push(Block::Paragraph(format!(
                "{} ({})",
                c.condition.label, t.spec.title
            )));
            page.push(Block::Figures(figures));
        }
    }
    Ok(page)
}
