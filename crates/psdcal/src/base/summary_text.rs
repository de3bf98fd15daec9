//! A data set's summary (`psdcal check`) as text: what was read, what was
//! dropped and why, and where on the sensor the points fall.

use std::fmt::Write as _;

use psdcal_io::{DataSetSummary, Warning};

/// The summary as text for people (what `psdcal check` prints): the
/// template, the images with the ranges of their points, what was dropped
/// and why, and a map of the sensor's coverage.
pub fn summary_text(s: &DataSetSummary) -> String {
    let mut out = String::new();
    // Writing to a String cannot fail.
    let _ = write_summary(&mut out, s);
    out
}

fn write_summary(out: &mut String, s: &DataSetSummary) -> std::fmt::Result {
    let lines = if s.template.lines.is_empty() {
        "no declared lines".to_string()
    } else {
        let list: Vec<String> = s
            .template
            .lines
            .iter()
            .map(|l| format!("{} ({})", l.name, l.leds))
            .collect();
        format!(
            "{} declared line{}: {}",
            list.len(),
            if list.len() == 1 { "" } else { "s" },
            list.join(", ")
        )
    };
    writeln!(
        out,
        "template:      {}: {} LEDs, {lines}",
        s.template.file, s.template.leds
    )?;
    writeln!(
        out,
        "observations:  {}: {} rows",
        s.observations_file, s.rows
    )?;
    writeln!(
        out,
        "sensor:        {} x {} mm active area",
        s.sensor.lx_mm, s.sensor.ly_mm
    )?;
    writeln!(out)?;
    let id_width = s
        .images
        .iter()
        .map(|i| i.id.chars().count())
        .chain([5])
        .max()
        .unwrap_or(5);
    writeln!(
        out,
        "{:<id_width$}  {:>6}  {:<20}  y range (mm)",
        "image", "points", "x range (mm)"
    )?;
    for image in &s.images {
        let (x, y) = match &image.bounds {
            Some(b) => (
                format!("{:.3} .. {:.3}", b.x_min_mm, b.x_max_mm),
                format!("{:.3} .. {:.3}", b.y_min_mm, b.y_max_mm),
            ),
            None => ("-".to_string(), "-".to_string()),
        };
        writeln!(
            out,
            "{:<id_width$}  {:>6}  {x:<20}  {y}",
            image.id, image.points
        )?;
    }
    writeln!(
        out,
        "total: {} image{}, {} points",
        s.images.len(),
        if s.images.len() == 1 { "" } else { "s" },
        s.total_points
    )?;
    writeln!(out)?;
    writeln!(out, "dropped:       {}", dropped(s))?;
    let c = &s.coverage;
    writeln!(
        out,
        "coverage:      {} of {} cells ({:.0}%) of a {n} x {n} grid over the active area",
        c.cells_covered,
        c.cells_per_side * c.cells_per_side,
        100.0 * c.fraction,
        n = c.cells_per_side
    )?;
    if let Some(b) = &c.bounds {
        writeln!(
            out,
            "bounding box:  x {:.3} .. {:.3} mm, y {:.3} .. {:.3} mm",
            b.x_min_mm, b.x_max_mm, b.y_min_mm, b.y_max_mm
        )?;
    }
    let border = format!("+{}+", "-".repeat(c.cells_per_side));
    writeln!(out, "      {border}")?;
    let map = c.ascii_map();
    let last = map.len().saturating_sub(1);
    for (i, row) in map.iter().enumerate() {
        let label = match i {
            0 => "+y",
            _ if i == last => "-y",
            _ => "",
        };
        writeln!(out, "  {label:>2}  |{row}|")?;
    }
    writeln!(out, "      {border}")?;
    let width = c.cells_per_side.saturating_sub(2);
    writeln!(out, "       -x{:>width$}", "+x")?;
    writeln!(out, "      ('#': at least one point in the cell)")
}

/// What was dropped and why, in one line.
fn dropped(s: &DataSetSummary) -> String {
    let off = s
        .warnings
        .iter()
        .filter(|w| matches!(w, Warning::PointOffSensor { .. }))
        .count();
    let images: Vec<String> = s
        .warnings
        .iter()
        .filter_map(|w| match w {
            Warning::TooFewPoints {
                image, count, min, ..
            } => Some(format!("image '{image}' ({count} of {min} points needed)")),
            _ => None,
        })
        .collect();
    let mut parts = Vec::new();
    if off > 0 {
        parts.push(format!(
            "{off} point{} off the active area",
            if off == 1 { "" } else { "s" }
        ));
    }
    if !images.is_empty() {
        parts.push(format!(
            "{} image{} with too few points: {}",
            images.len(),
            if images.len() == 1 { "" } else { "s" },
            images.join(", ")
        ));
    }
    if parts.is_empty() {
        "nothing".to_string()
    } else {
        format!(
            "{} ({} points in all; see the warnings)",
            parts.join("; "),
            s.dropped_points
        )
    }
}
