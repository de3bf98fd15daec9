//! The page of `psdcal psd-map --report`: a PSD map fitted to a lensless
//! scan, from plain content ([`PsdMapReport`]) the caller fills: what was
//! fitted in a list (model, cross-validated RMS, noise, rejected points,
//! the scan's hull), then the figures (the field, its size, the scan's
//! residuals), drawn by [`Plot`]s like the calibration report's, then the
//! model choice and the cross-validation's candidates in a table.

use crate::calibration::Plot;
use crate::html::{Block, Page, Table};

/// A PSD map report's content.
#[derive(Debug, Clone, PartialEq)]
pub struct PsdMapReport {
    /// Page title.
    pub title: String,
    /// The fit in a few lines (model, CV RMS, noise, rejected points, hull).
    pub summary: Vec<String>,
    /// Every candidate model with its cross-validated RMS.
    pub cross_validation: Table,
    /// How the model was chosen, one paragraph.
    pub choice: String,
    /// The figures.
    pub plots: Vec<Plot>,
    /// Provenance: version, command, the scan with its SHA-256.
    pub provenance: Option<Table>,
}

/// The page; `svgs` are the plots' SVG texts, in order.
pub fn psd_map_page(report: &PsdMapReport, svgs: &[String]) -> Page {
    let mut page = Page::new(&report.title);
    page.push(Block::List(report.summary.clone()));
    page.push(Block::Heading("Plots".into()));
    page.push(Block::Figures(
        svgs.iter()
            .zip(&report.plots)
            .map(|(svg, p)| (svg.clone(), p.caption.clone()))
            .collect(),
    ));
    page.push(Block::Heading("Model choice".into()));
    page.push(Block::Paragraph(report.choice.clone()));
    page.push(Block::Table(report.cross_validation.clone()));
    if let Some(t) = &report.provenance {
        page.push(Block::Heading("Provenance".into()));
        page.push(Block::Table(t.clone()));
    }
    page
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_page_holds_the_summary_the_table_and_escaped_text() {
        let report = PsdMapReport {
            title: "PSD map from <scan>.csv".into(),
            summary: vec!["cross-validated RMS error 0.412 µm".into()],
            cross_validation: Table {
                caption: "Cross-validation".into(),
                headers: vec!["model".into(), "CV RMS (µm)".into()],
                rows: vec![vec!["poly:3".into(), "0.412".into()]],
            },
            choice: "the simplest within one standard error".into(),
            plots: Vec::new(),
            provenance: None,
        };
        let html = psd_map_page(&report, &[]).render();
        assert!(html.contains("PSD map from &lt;scan&gt;.csv"));
        assert!(html.contains("<li>cross-validated RMS error 0.412 µm</li>"));
        assert!(html.contains("<td>poly:3</td>") && html.contains("0.412"));
        assert!(!html.contains("<script"));
    }
}
