//! The study page (issue 18): numbers rounded by their spread, checked
//! against the statistics by parsing the printed text back; the bias with
//! its sign and colour; warnings first; no internal names.

use psdcal_report::*;

/// `(value, spread)` read back from `a ± b` or `(a ± b) × 10ⁿ`, with the
/// decimals of each as printed.
fn parse(cell: &str) -> (f64, f64, usize, usize) {
    let (body, exponent) = match cell.split_once(") × 10") {
        Some((b, e)) => {
            let digits: String = e
                .chars()
                .map(|c| match c {
                    '⁻' => '-',
                    c => "⁰¹²³⁴⁵⁶⁷⁸⁹"
                        .chars()
                        .position(|d| d == c)
                        .map_or(c, |p| char::from(b'0' + p as u8)),
                })
                .collect();
            (
                b.trim_start_matches(['+', '(']),
                digits.parse::<i32>().unwrap(),
            )
        }
        None => (cell.trim_start_matches('+'), 0),
    };
    let (a, b) = body.split_once(" ± ").unwrap();
    let decimals = |s: &str| s.split_once('.').map_or(0, |(_, d)| d.len());
    let scale = 10f64.powi(exponent);
    let a_value: f64 = a.parse::<f64>().unwrap() * scale;
    let b_value: f64 = b.parse::<f64>().unwrap() * scale;
    (a_value, b_value, decimals(a), decimals(b))
}

/// Significant digits of a printed number (leading zeros do not count).
fn significant(text: &str) -> usize {
    text.trim_start_matches(['-', '+'])
        .chars()
        .filter(char::is_ascii_digit)
        .skip_while(|c| *c == '0')
        .count()
}

#[test]
fn estimates_are_rounded_by_their_spread_to_two_significant_digits() {
    let cases = [
        (24.98349, 0.142_41),
        (2.015_27e-3, 8.041e-6),
        (-3.683e-7, 5.827e-7),
        (0.522_17, 0.030_76),
        (1234.567, 25.4),
        (-0.700_71, 0.013_88),
        (3.1e6, 2.2e4),
    ];
    for (mean, std) in cases {
        let cell = estimate_cell(Some(StudyStats { mean, std, n: 200 }));
        let (a, b, da, db) = parse(&cell);
        // The spread keeps two significant digits…
        let spread_text = cell.split(" ± ").nth(1).unwrap().split(')').next().unwrap();
        assert_eq!(significant(spread_text), 2, "{cell}");
        // …the mean is printed to the same decimal place…
        assert_eq!(da, db, "{cell}");
        // …and both are the statistics rounded there: within half a unit
        // of the last printed digit.
        let unit = b / spread_text.parse::<f64>().unwrap() * 10f64.powi(-(db as i32));
        assert!(
            (a - mean).abs() <= 0.5 * unit * (1.0 + 1e-9),
            "{cell}: {a} vs {mean}"
        );
        assert!(
            (b - std).abs() <= 0.5 * unit * (1.0 + 1e-9),
            "{cell}: {b} vs {std}"
        );
    }
    // One trial or no spread: the mean alone; nothing: a dash.
    let one = estimate_cell(Some(StudyStats {
        mean: 8.0,
        std: 0.0,
        n: 1,
    }));
    assert!(!one.contains('±') && one.starts_with("8.0"), "{one}");
    assert_eq!(estimate_cell(None), "–");
}

#[test]
fn bias_is_signed_rounded_by_its_standard_error_and_shaded_by_the_spread() {
    let (mean, std, n, truth) = (25.0841, 0.3, 100usize, 25.0);
    let (text, shade) = bias_cell(Some(StudyStats { mean, std, n }), Some(truth));
    assert!(text.starts_with('+'), "{text}");
    let (a, b, da, db) = parse(&text);
    let se = std / (n as f64).sqrt();
    assert_eq!(da, db);
    assert!((a - (mean - truth)).abs() <= 0.0005 + 1e-12, "{text}");
    assert!((b - se).abs() <= 0.0005 + 1e-12, "{text}");
    let expected = (mean - truth) / std / BIAS_FULL_SHADE;
    assert!((shade.unwrap() - expected).abs() < 1e-12);
    // Far below the truth: full blue; no spread: no shade.
    let (text, shade) = bias_cell(
        Some(StudyStats {
            mean: 20.0,
            std: 0.1,
            n: 4,
        }),
        Some(truth),
    );
    assert!(text.starts_with('-') && shade == Some(-1.0), "{text}");
    let (_, shade) = bias_cell(
        Some(StudyStats {
            mean: 20.0,
            std: 0.0,
            n: 1,
        }),
        Some(truth),
    );
    assert_eq!(shade, None);
    assert_eq!(bias_cell(None, Some(1.0)).0, "–");
}

fn content() -> StudyContent {
    let stats = |mean: f64, std: f64| Some(StudyStats { mean, std, n: 3 });
    StudyContent {
        title: "psdcal study".into(),
        intro: "intro".into(),
        summary: vec![("seed".into(), "1".into())],
        reading: vec!["read me".into()],
        warnings: Vec::new(),
        tables: vec![StudyTable {
            title: "Table 5 (lens 1)".into(),
            rows: vec![
                StudyRow {
                    label: "radial distortion k1".into(),
                    unit: "mm^-2".into(),
                    bias: true,
                },
                StudyRow {
                    label: "iterations".into(),
                    unit: String::new(),
                    bias: false,
                },
            ],
            histogram_rows: vec![0],
            columns: vec![
                StudyColumn {
                    label: "40 dB".into(),
                    ideal: vec![Some(2e-3), None],
                    stats: vec![stats(2.015e-3, 8.0e-6), stats(12.0, 2.0)],
                    trials: 4,
                    failures: 1,
                    failure_reasons: vec!["refinement did not converge".into()],
                    values: vec![vec![2.01e-3, 2.015e-3, 2.02e-3], vec![10.0, 12.0, 14.0]],
                    paper: vec![Some((1.996e-3, Some(4.8e-5))), Some((35.6, Some(12.0)))],
                },
                StudyColumn {
                    label: "no noise".into(),
                    ideal: vec![Some(2e-3), None],
                    stats: vec![None, None],
                    trials: 4,
                    failures: 4,
                    failure_reasons: vec!["no closed form".into()],
                    values: vec![Vec::new(), Vec::new()],
                    paper: vec![None, None],
                },
            ],
            notes: vec!["a note".into()],
        }],
        maps: Vec::new(),
        extra: Vec::new(),
    }
}

#[test]
fn the_page_warns_first_and_speaks_in_words() {
    let html = study_page(&content()).unwrap().render();
    let warnings = html.find("<h2>Warnings</h2>").unwrap();
    let run = html.find("<h2>What was run</h2>").unwrap();
    let table = html.find("<h2>Table 5 (lens 1)</h2>").unwrap();
    assert!(warnings < run && run < table);
    assert!(html.contains("40 dB: 1 of 4 trials failed: refinement did not converge"));
    assert!(html.contains("no noise: no result, all 4 trials failed: no closed form"));
    assert!(html.contains("Only 4 trials per condition"));
    // Units as printed, the row in words, numbers rounded by the spread.
    assert!(html.contains("radial distortion k1 (mm⁻²)"));
    assert!(html.contains("(2.0150 ± 0.0080) × 10⁻³"), "{html}");
    assert!(html.contains("The paper&#39;s numbers"));
    assert!(html.contains("(1.996 ± 0.048) × 10⁻³"));
    // The bias table leaves out what has no truth or is no parameter.
    let bias = &html[html.find("Bias: mean").unwrap()..];
    let bias = &bias[..bias.find("</table>").unwrap()];
    assert!(!bias.contains("iterations"));
    assert!(bias.contains("style=\"background:"));
    let text = match (html.find("<svg"), html.rfind("</svg>")) {
        (Some(a), Some(b)) => format!("{}{}", &html[..a], &html[b..]),
        _ => html.clone(),
    };
    for internal in ["mm^-2", "e-3", "Some(", "None", "Quantity", "FirstStage"] {
        assert!(!text.contains(internal), "{internal}");
    }
    // Every trial succeeded: it says so.
    let mut clean = content();
    clean.tables[0].columns.truncate(1);
    clean.tables[0].columns[0].failures = 0;
    clean.tables[0].columns[0].trials = 200;
    let html = study_page(&clean).unwrap().render();
    assert!(html.contains("None: every trial of every condition succeeded."));
}
