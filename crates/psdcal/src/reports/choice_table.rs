//! The report's table of the model choice (docs/model.md §4.8): each
//! candidate the forward selection scored, read from calibration.json's
//! `fit.model_choice`.

use psdcal_report::{num, Table};
use serde_json::Value;

/// The table of the candidates and the choice; `None` for a fit of given
/// parameters.
pub(crate) fn choice_table(choice: Option<&Value>) -> Option<Table> {
    let choice = choice?;
    let chosen = words(&choice["chosen"]);
    let caption = match choice["skipped"].as_str() {
        Some(reason) => format!("The model: {chosen} (no choice by held-out error: {reason})"),
        None => format!(
            "The model the data chose: {chosen}. Each candidate adds one group to the set \
             before it; it is taken when its score statistic shows it in the data and it \
             lowers the error on images the fit did not see beyond that error's noise"
        ),
    };
    let rows = choice["candidates"]
        .as_array()
        .map(|all| all.iter().enumerate().map(candidate_row).collect())
        .unwrap_or_default();
    Some(Table {
        caption,
        headers: [
            "candidate",
            "score statistic",
            "held-out RMS (°)",
            "ln ratio per image",
            "",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    })
}

/// One candidate's row.
fn candidate_row((k, c): (usize, &Value)) -> Vec<String> {
    let held_out = c["held_out_rms_deg"].as_f64();
    let status = match (k, c["accepted"].as_bool(), held_out) {
        (0, _, _) => "the start",
        (_, Some(true), _) => "taken",
        (_, _, None) => "not refitted (no evidence)",
        _ => "not taken",
    };
    let ratio = match (c["log_ratio"].as_f64(), c["log_ratio_se"].as_f64()) {
        (Some(l), Some(se)) => format!("{l:+.3} ± {se:.3}"),
        _ => String::new(),
    };
    vec![
        words(&c["free"]),
        c["score_statistic"].as_f64().map(num).unwrap_or_default(),
        held_out.map(|v| format!("{v:.5}")).unwrap_or_default(),
        ratio,
        status.to_string(),
    ]
}

/// A list of names as `f, cx, cy`.
fn words(names: &Value) -> String {
    names
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(Value::as_str)
                .collect::<Vec<_>>()
                .join(", ")
        })
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_candidate_is_a_row_with_its_outcome() {
        let choice = serde_json::json!({
            "chosen": ["f", "cx", "a"],
            "skipped": null,
            "candidates": [
                {"free": ["f", "cx"], "score_statistic": null, "held_out_rms_deg": 0.05,
                 "log_ratio": null, "log_ratio_se": null, "accepted": true},
                {"free": ["f", "cx", "a"], "score_statistic": 23.6, "held_out_rms_deg": 0.049,
                 "log_ratio": -0.2, "log_ratio_se": 0.05, "accepted": true},
                {"free": ["f", "cx", "k3"], "score_statistic": 0.2, "held_out_rms_deg": null,
                 "log_ratio": null, "log_ratio_se": null, "accepted": false}
            ]
        });
        let table = choice_table(Some(&choice)).expect("a table");
        assert!(table.caption.contains("f, cx, a"), "{}", table.caption);
        let outcomes: Vec<&str> = table.rows.iter().map(|r| r[4].as_str()).collect();
        assert_eq!(
            outcomes,
            ["the start", "taken", "not refitted (no evidence)"]
        );
        assert_eq!(table.rows[1][3], "-0.200 ± 0.050");
        assert!(choice_table(None).is_none());
    }
}
