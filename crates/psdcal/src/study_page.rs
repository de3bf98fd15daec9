//! The study's results as the plain data psdcal-report draws its page from.

use psdcal_report::{Fig9Map, Page, ReportError, StudyColumn, StudyStats, StudyTable};
use psdcal_study::fig9::Figure9Map;
use psdcal_study::{Quantity, TableResult};

/// Parameters that get histograms, in the order they are shown.
const HISTOGRAM_ROWS: [Quantity; 5] = [
    Quantity::F,
    Quantity::Cx,
    Quantity::Cy,
    Quantity::K1,
    Quantity::K2,
];

/// A study table as plain data.
pub fn study_table(t: &TableResult) -> StudyTable {
    StudyTable {
        title: t.spec.title.clone(),
        rows: t.rows.iter().map(|q| q.label().to_string()).collect(),
        histogram_rows: HISTOGRAM_ROWS
            .iter()
            .filter_map(|q| t.rows.iter().position(|x| x == q))
            .collect(),
        columns: t
            .columns
            .iter()
            .map(|c| StudyColumn {
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
            })
            .collect(),
    }
}

/// A Figure 9 map as plain data.
pub fn fig9_map(m: &Figure9Map) -> Fig9Map {
    Fig9Map {
        lens: m.lens,
        condition: m.condition.clone(),
        offsets: m.offsets.clone(),
        grid: m.grid.clone(),
        max_aoa_deg: m.max_aoa_deg,
        max_position_mm: m.max_position_mm,
        mean_aoa_deg: m.mean_aoa_deg,
    }
}

/// The study page.
pub fn study_page(
    title: &str,
    intro: &str,
    tables: &[TableResult],
    maps: &[Figure9Map],
) -> Result<Page, ReportError> {
    let tables: Vec<StudyTable> = tables.iter().map(study_table).collect();
    let maps: Vec<Fig9Map> = maps.iter().map(fig9_map).collect();
    psdcal_report::study_page(title, intro, &tables, &maps)
}
