//! Study tables as Markdown and CSV, psdcal's numbers next to the paper's.
//!
//! Markdown: one table per study table, rows the reported quantities, and per
//! condition two columns, psdcal's `mean (std)` and the paper's. CSV (long
//! form, one row per table × condition × quantity):
//! `table,condition,quantity,ideal,mean,std,trials,failures,paper_mean,paper_std`.

use std::fmt::Write as _;

use crate::paper;
use crate::study::{Quantity, TableResult};

/// `mean (std)` with four significant digits.
fn cell(mean: f64, std: Option<f64>) -> String {
    match std {
        Some(s) => format!("{} ({})", num(mean), num(s)),
        None => num(mean),
    }
}

/// A number with four significant digits, in plain or scientific notation.
pub fn num(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if (1e-2..1e4).contains(&x.abs()) {
        let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
        format!("{x:.digits$}")
    } else {
        format!("{x:.3e}")
    }
}

/// The paper's cell for a table, column and quantity: its mean and, where
/// printed, its standard deviation.
pub fn paper_cell(table: &TableResult, column: usize, q: Quantity) -> Option<(f64, Option<f64>)> {
    let t = paper::table(table.spec.paper?)?;
    let row = match q {
        Quantity::Cx => 0,
        Quantity::Cy => 1,
        Quantity::F => 2,
        Quantity::K1 => 3,
        Quantity::K2 => 4,
        Quantity::Residual => 5,
        Quantity::Iterations => 6,
        Quantity::AoaRms => return None,
    };
    t.columns.get(column)?.cells.get(row).copied().flatten()
}

/// One table as Markdown.
pub fn markdown(table: &TableResult) -> String {
    let mut out = String::new();
    let _ = write_markdown(&mut out, table);
    out
}

fn write_markdown(out: &mut String, table: &TableResult) -> std::fmt::Result {
    writeln!(out, "### {}\n", table.spec.title)?;
    write!(out, "| | Ideal |")?;
    for c in &table.columns {
        write!(out, " {} | paper |", c.condition.label)?;
    }
    writeln!(out)?;
    write!(out, "|---|---|")?;
    for _ in &table.columns {
        write!(out, "---|---|")?;
    }
    writeln!(out)?;
    for (r, q) in table.rows.iter().enumerate() {
        let ideal = table.columns.first().and_then(|c| c.condition.ideal(*q));
        write!(out, "| {} | {} |", q.label(), ideal.map_or("–".into(), num))?;
        for (k, c) in table.columns.iter().enumerate() {
            let ours =
                c.stats[r].map_or("–".into(), |s| cell(s.mean, (s.n > 1).then_some(s.std)));
            let theirs = paper_cell(table, k, *q).map_or("–".into(), |(m, s)| cell(m, s));
            write!(out, " {ours} | {theirs} |")?;
        }
        writeln!(out)?;
    }
    let trials = table.columns.first().map_or(0, |c| c.trials);
    writeln!(
        out,
        "\npsdcal: mean (std) over {trials} trials per column; paper: as printed."
    )?;
    for c in table.columns.iter().filter(|c| c.failures > 0) {
        writeln!(
            out,
            "- {}: {} of {} trials failed (e.g. {})",
            c.condition.label,
            c.failures,
            c.trials,
            c.failure_reasons.first().map_or("", String::as_str)
        )?;
    }
    if let Some(t) = table.spec.paper.and_then(paper::table) {
        for note in t.notes {
            writeln!(out, "- Paper: {note}")?;
        }
    }
    writeln!(out)
}

/// The CSV header.
pub const CSV_HEADER: &str =
    "table,condition,quantity,ideal,mean,std,trials,failures,paper_mean,paper_std";

/// One table's CSV rows (without the header).
pub fn csv_rows(table: &TableResult) -> String {
    let mut out = String::new();
    for (k, c) in table.columns.iter().enumerate() {
        for (r, q) in table.rows.iter().enumerate() {
            let opt = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:e}"));
            let s = c.stats[r];
            let p = paper_cell(table, k, *q);
            let _ = writeln!(
                out,
                "{},\"{}\",{:?},{},{},{},{},{},{},{}",
                table.spec.id,
                c.condition.label,
                q,
                opt(c.condition.ideal(*q)),
                opt(s.map(|s| s.mean)),
                opt(s.map(|s| s.std)),
                c.trials,
                c.failures,
                opt(p.map(|p| p.0)),
                opt(p.and_then(|p| p.1)),
            );
        }
    }
    out
}
