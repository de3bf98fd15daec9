//! No axis of any plot repeats a tick label (issue 18): every plot function
//! is drawn over awkward ranges (tiny widths far from zero, huge values,
//! negative spans, histograms of a few counts), and the tick labels of each
//! axis — the texts sharing one baseline (x axis) or one right edge (y axis
//! and colour bar) — must all differ; count axes print integers only.

use std::collections::HashMap;

use psdcal_report::*;

/// `(x, y, text)` of every unrotated `<text>` element.
fn texts(svg: &str) -> Vec<(String, String, String)> {
    let mut out = Vec::new();
    let mut rest = svg;
    while let Some(start) = rest.find("<text") {
        let after = &rest[start..];
        let open_end = after.find('>').unwrap();
        let tag = &after[..open_end];
        let close = after.find("</text>").unwrap();
        let body = after[open_end + 1..close].trim().to_string();
        let attr = |name: &str| -> String {
            let key = format!(" {name}=\"");
            tag.find(&key)
                .map(|i| {
                    let v = &tag[i + key.len()..];
                    v[..v.find('"').unwrap()].to_string()
                })
                .unwrap_or_default()
        };
        if !tag.contains("rotate") && !body.is_empty() {
            out.push((attr("x"), attr("y"), body));
        }
        rest = &after[close..];
    }
    out
}

fn assert_distinct_ticks(svg: &str, what: &str) {
    let t = texts(svg);
    assert!(t.len() > 6, "{what}: too few texts");
    for axis in 0..2 {
        let mut groups: HashMap<&str, Vec<&str>> = HashMap::new();
        for (x, y, body) in &t {
            let key = if axis == 0 { y } else { x };
            groups.entry(key.as_str()).or_default().push(body.as_str());
        }
        for (at, labels) in groups {
            let mut seen = std::collections::HashSet::new();
            for l in &labels {
                assert!(
                    seen.insert(*l),
                    "{what}: the axis at {} {at} repeats the tick label {l:?}: {labels:?}",
                    if axis == 0 { "y =" } else { "x =" }
                );
            }
        }
    }
}

/// Ranges that once printed the same label at every tick.
fn ranges() -> Vec<(f64, f64)> {
    vec![
        (3.0e-5, 3.0e-5 + 2e-9),
        (-1e-7, 1e-7),
        (0.0, 1.0),
        (-4.95, 4.95),
        (2499.9, 2500.1),
        (1e6, 1e6 + 3.0),
        (-3e7, 5e8),
    ]
}

fn line(range: (f64, f64), n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|k| {
            let u = k as f64 / (n - 1) as f64;
            (
                range.0 + u * (range.1 - range.0),
                range.1 - u * (range.1 - range.0),
            )
        })
        .collect()
}

#[test]
fn no_axis_of_any_plot_repeats_a_tick_label() {
    for r in ranges() {
        let frame = Frame::new("t", "x", "y", r, r);
        let pts = line(r, 12);
        let sets = vec![PointSet {
            label: "a".into(),
            points: pts.clone(),
        }];
        let arrows: Vec<Arrow> = pts
            .iter()
            .map(|&at| Arrow {
                at,
                delta: (1e-3 * (r.1 - r.0), 0.0),
            })
            .collect();
        let w = r.1 - r.0;
        let cells: Vec<HeatCell> = (0..25)
            .map(|k| HeatCell {
                x: r.0 + w * (k % 5) as f64 / 4.0,
                y: r.0 + w * (k / 5) as f64 / 4.0,
                value: r.0 + w * k as f64 / 24.0,
            })
            .collect();
        let set = ArrowSet {
            label: "a".into(),
            arrows: arrows.clone(),
        };
        let svgs = [
            ("coverage", coverage_svg(&sets, 9.0, 9.0, &frame).unwrap()),
            ("residuals", residuals_svg(&[set], 1.0, &frame).unwrap()),
            (
                "distortion",
                distortion_field_svg(&arrows, 1.0, &[], &frame).unwrap(),
            ),
            ("spiral", spiral_svg(&pts, &pts, &frame).unwrap()),
            ("lines", line_plot_svg(&sets, &frame).unwrap()),
            ("scatter", scatter_svg(&sets, &frame).unwrap()),
            (
                "heat map",
                heat_map_svg(&cells, (w / 4.0, w / 4.0), &frame, "v").unwrap(),
            ),
        ];
        for (what, svg) in &svgs {
            assert_distinct_ticks(svg, &format!("{what} over {r:?}"));
        }
        let values: Vec<f64> = pts.iter().map(|p| p.0).collect();
        for n in [1usize, 3, 12] {
            let bars: Vec<f64> = values[..n].iter().map(|v| v.abs()).collect();
            let svg = bar_chart_svg(&bars, &bar_frame("b", "image", "rms", &bars)).unwrap();
            assert_distinct_ticks(&svg, &format!("bars of {n} over {r:?}"));
        }
        for n in [1usize, 3, 12] {
            let svg = histogram_svg(&values[..n], Some(values[0]), 10, "h", "x").unwrap();
            assert_distinct_ticks(&svg, &format!("histogram of {n} over {r:?}"));
        }
    }
}

#[test]
fn count_axes_print_integers_only() {
    for v in [0.0, 0.5, 1.0, 1.5, 2.0, 17.0] {
        let l = count_label(v);
        assert!(l.is_empty() || l.parse::<u64>().is_ok(), "{v}: {l}");
    }
    assert_eq!(count_label(2.0), "2");
    assert_eq!(count_label(0.5), "");
    let svg = histogram_svg(&[1.0, 2.0, 2.0], None, 3, "h", "x").unwrap();
    for (_, _, body) in texts(&svg) {
        assert_ne!(body, "0.5");
        assert_ne!(body, "1.5");
    }
}

#[test]
fn bar_charts_have_one_bar_per_value_and_integer_item_ticks() {
    let values: Vec<f64> = (0..40).map(|k| 1.0 + (k % 7) as f64).collect();
    let svg = bar_chart_svg(&values, &bar_frame("b", "image", "rms", &values)).unwrap();
    let empty = bar_chart_svg(&[], &bar_frame("b", "image", "rms", &[])).unwrap();
    assert_eq!(
        svg.matches("<rect").count() - empty.matches("<rect").count(),
        40
    );
    assert_distinct_ticks(&svg, "40 bars");
    // The x axis: the lowest row of three or more texts; integers only.
    let t = texts(&svg);
    let mut rows: HashMap<&str, Vec<&str>> = HashMap::new();
    for (_, y, body) in &t {
        rows.entry(y.as_str()).or_default().push(body.as_str());
    }
    let (_, x_axis) = rows
        .into_iter()
        .filter(|(_, v)| v.len() >= 3)
        .max_by(|a, b| {
            a.0.parse::<f64>()
                .unwrap()
                .total_cmp(&b.0.parse::<f64>().unwrap())
        })
        .unwrap();
    for label in x_axis {
        assert!(label.parse::<u64>().is_ok(), "{label}");
    }
}

#[test]
fn tick_labels_are_short_and_distinct_at_their_step() {
    assert_eq!(tick_label(0.25, (0.0, 1.0)), "0.25");
    assert_eq!(tick_label(-0.0, (-1.0, 1.0)), "0.0");
    assert_eq!(tick_label(2500.0, (2000.0, 3000.0)), "2500");
    assert_ne!(
        tick_label(3.0e-5, (3.0e-5, 3.0e-5 + 2e-9)),
        tick_label(3.0e-5 + 2.5e-10, (3.0e-5, 3.0e-5 + 2e-9))
    );
}

/// The `<svg>…</svg>` figures of a page.
fn page_svgs(html: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = html;
    while let Some(start) = rest.find("<svg") {
        let end = rest[start..].find("</svg>").unwrap() + start + 6;
        out.push(&rest[start..end]);
        rest = &rest[end..];
    }
    out
}

/// Deterministic, roughly normal values: `mean + std·z` over a fixed
/// sequence of `z` with mean 0 (a sum of uniforms).
fn spread(mean: f64, std: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| {
            let z: f64 = (1..=4)
                .map(|j| ((k * 7919 * j + 13 * j) % 1000) as f64 / 1000.0 - 0.5)
                .sum::<f64>();
            mean + std * z * 1.7
        })
        .collect()
}

/// A study table over values like the study's own: every column
/// `(label, n, scale of the spread)`.
pub fn study_table_of(columns: &[(&str, usize, f64)]) -> StudyTable {
    let rows: [(&str, &str, f64, f64); 5] = [
        ("focal length f", "mm", 25.0, 0.14),
        ("optical centre Cx", "mm", 0.5, 0.03),
        ("optical centre Cy", "mm", -0.7, 0.014),
        ("radial distortion k1", "mm^-2", 2.0e-3, 8.0e-6),
        ("radial distortion k2", "mm^-4", 0.0, 5.8e-7),
    ];
    StudyTable {
        title: "Table 9 (lens 1): the conditions compared".into(),
        rows: rows
            .iter()
            .map(|(l, u, _, _)| StudyRow {
                label: l.to_string(),
                unit: u.to_string(),
                bias: true,
            })
            .collect(),
        histogram_rows: vec![0, 1, 2, 3, 4],
        columns: columns
            .iter()
            .map(|&(label, n, scale)| {
                let values: Vec<Vec<f64>> = rows
                    .iter()
                    .map(|(_, _, t, s)| spread(t + 0.3 * s, s * scale, n))
                    .collect();
                let stats = values
                    .iter()
                    .map(|v| {
                        let m = v.iter().sum::<f64>() / v.len() as f64;
                        let var = if v.len() > 1 {
                            v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64
                        } else {
                            0.0
                        };
                        Some(StudyStats {
                            mean: m,
                            std: var.sqrt(),
                            n: v.len(),
                        })
                    })
                    .collect();
                StudyColumn {
                    label: label.into(),
                    ideal: rows.iter().map(|r| Some(r.2)).collect(),
                    stats,
                    trials: n + 1,
                    failures: 1,
                    failure_reasons: vec!["refinement did not converge".into()],
                    values,
                    paper: rows.iter().map(|r| Some((r.2, Some(r.3)))).collect(),
                }
            })
            .collect(),
        notes: Vec::new(),
    }
}

/// A Figure 9 map over a 41 × 41 grid whose errors span `[lo, hi]`.
pub fn fig9_map_of(lo: f64, hi: f64) -> Fig9Map {
    let grid = (0..41 * 41)
        .map(|k| {
            let (i, j) = ((k % 41) as f64, (k / 41) as f64);
            let (x, y) = (-4.5 + 9.0 * i / 40.0, -4.5 + 9.0 * j / 40.0);
            let t = (x.hypot(y) / 6.4).min(1.0);
            [
                x,
                y,
                lo + (hi - lo) * t,
                5000.0 * (lo + (hi - lo) * t).to_radians(),
            ]
        })
        .collect();
    Fig9Map {
        lens: 1,
        condition: "40 dB".into(),
        offsets: vec![Fig9Offset {
            name: "focal length f".into(),
            delta: 0.31,
            unit: "mm".into(),
        }],
        grid,
        max_aoa_deg: hi,
        max_position_mm: 5000.0 * hi.to_radians(),
        mean_aoa_deg: 0.5 * (lo + hi),
    }
}

#[test]
fn no_axis_of_any_plot_on_the_study_page_repeats_a_tick_label() {
    let table = study_table_of(&[
        ("40 dB", 200, 1.0),
        ("a tiny spread", 40, 1e-6),
        ("three trials", 3, 1.0),
        ("one trial", 1, 1.0),
        ("all equal", 5, 0.0),
        ("wide", 12, 1e3),
    ]);
    let content = StudyContent {
        title: "study".into(),
        intro: String::new(),
        summary: Vec::new(),
        reading: Vec::new(),
        warnings: Vec::new(),
        tables: vec![table],
        maps: vec![
            fig9_map_of(0.21, 0.34),
            fig9_map_of(1e-4, 1.0001e-4),
            fig9_map_of(2.0, 28.0),
        ],
        extra: Vec::new(),
    };
    let html = study_page(&content).unwrap().render();
    let svgs = page_svgs(&html);
    // 6 maps (AoA and position for 3 conditions) + 6 × 5 histograms.
    assert_eq!(svgs.len(), 6 + 30);
    for (k, svg) in svgs.iter().enumerate() {
        assert_distinct_ticks(svg, &format!("study page figure {k}"));
    }
}
