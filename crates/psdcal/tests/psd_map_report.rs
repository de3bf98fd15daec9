//! `psd-map --report DIR` (issue 14): the page and its figures exist and are
//! well formed (every SVG balanced, every PNG of the SVG's size, the page
//! holding each figure and its caption, no script), the numbers shown are
//! psd_map.json's read back here on their own (the cross-validated RMS,
//! every candidate's row, the residual arrows' lengths in the SVG against
//! the file's residuals in µm, the worst cell's RMS recomputed from the
//! file), outliers drawn apart, and a report that would overwrite the scan
//! or psd_map.json, or whose folder cannot be made, refused before anything
//! is written.

use psdcal_testkit::svg::polylines;
use std::path::Path;

use psdcal::{
    psd_map_from_scan, scan_samples, PsdGeometry, PsdMapModel, PsdMapRequest, ScanRequest,
    PSD_MAP_PAGE, SCAN_SUMMARY_CELLS,
};

const PLOTS: [&str; 6] = [
    "psd_map_field",
    "psd_map_magnitude",
    "psd_map_scan_points",
    "psd_map_residuals",
    "psd_map_residual_rms",
    "psd_map_residual_histogram",
];

/// Lines of scan.csv (from 2: the header is line 1) whose point is moved
/// 40 µm along x: outliers the fit must reject.
const OUTLIER_LINES: [usize; 2] = [100, 201];

/// A 0.5 mm raster (19 × 19) through the simulated non-linearity at 50 dB,
/// with two outliers, written to `path`.
fn write_scan(path: &Path) {
    let scan = scan_samples(&ScanRequest {
        step_mm: 0.5,
        stage_sigma_um: 0.3,
        snr_db: Some(50.0),
        nonlinearity: true,
        geometry: PsdGeometry::default(),
        seed: 11,
        out: path.to_path_buf(),
    })
    .unwrap();
    let stage: Vec<_> = scan.samples.iter().map(|s| s.stage).collect();
    let mut measured: Vec<_> = scan.samples.iter().map(|s| s.measured).collect();
    for line in OUTLIER_LINES {
        measured[line - 2].x += 0.040;
    }
    psdcal_io::write_scan(path, &stage, Some(&measured), None).unwrap();
}

fn request(scan: &Path, report: &Path) -> PsdMapRequest {
    PsdMapRequest {
        scan: scan.to_path_buf(),
        model: PsdMapModel::Auto,
        geometry: PsdGeometry::default(),
        seed: 0,
        command: "psdcal psd-map --report".into(),
        report: Some(report.to_path_buf()),
        limits: Default::default(),
        force: false,
    }
}

/// Whether `text` is well-formed markup: every element closed in order
/// (`<a …>…</a>`, `<a …/>`, HTML's void elements alone), declarations,
/// comments and text between.
fn well_formed(text: &str) -> Result<(), String> {
    let mut open: Vec<String> = Vec::new();
    let mut rest = text;
    while let Some(start) = rest.find('<') {
        rest = &rest[start..];
        if let Some(body) = rest.strip_prefix("<!--") {
            let end = body.find("-->").ok_or("unclosed comment")?;
            rest = &body[end + 3..];
            continue;
        }
        let end = rest.find('>').ok_or("unclosed tag")?;
        let tag = &rest[1..end];
        rest = &rest[end + 1..];
        if tag.starts_with('?') || tag.starts_with('!') {
            continue;
        }
        if let Some(name) = tag.strip_prefix('/') {
            match open.pop() {
                Some(o) if o == name.trim() => {}
                other => return Err(format!("</{name}> closes {other:?}")),
            }
        } else if !tag.ends_with('/') {
            let name = tag.split_whitespace().next().ok_or("empty tag")?;
            // HTML's void elements have no end tag.
            if !["meta", "br", "hr", "img", "link", "input"].contains(&name) {
                open.push(name.to_string());
            }
        }
    }
    if open.is_empty() {
        Ok(())
    } else {
        Err(format!("unclosed {open:?}"))
    }
}

/// The number printed after `prefix` in `text` (up to a space, a quote or
/// a tag).
fn number_after(text: &str, prefix: &str) -> f64 {
    let at = text.find(prefix).unwrap_or_else(|| panic!("no '{prefix}'")) + prefix.len();
    let tail = &text[at..];
    let end = tail.find([' ', '"', '<']).unwrap();
    tail[..end]
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("{prefix}{}", &tail[..end]))
}

#[test]
fn the_report_shows_the_files_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("scan.csv");
    write_scan(&scan);
    let report = dir.path().join("report");
    let map_path = dir.path().join("psd_map.json");
    let outcome = psd_map_from_scan(&request(&scan, &report)).unwrap();
    outcome.write(&map_path).unwrap();
    assert!(outcome.text.contains(PSD_MAP_PAGE), "{}", outcome.text);

    // Files: the page and every figure as SVG and PNG, well formed.
    let html = std::fs::read_to_string(report.join(PSD_MAP_PAGE)).unwrap();
    well_formed(&html).unwrap();
    assert!(!html.to_lowercase().contains("<script"));
    let mut svgs = std::collections::HashMap::new();
    for name in PLOTS {
        let svg = std::fs::read_to_string(report.join(format!("{name}.svg"))).unwrap();
        well_formed(&svg).unwrap_or_else(|e| panic!("{name}.svg: {e}"));
        assert!(svg.contains("<svg") && svg.contains("</svg>"), "{name}");
        let png = std::fs::read(report.join(format!("{name}.png"))).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{name}.png");
        assert_eq!(&png[12..16], b"IHDR");
        let size = |at: usize| u32::from_be_bytes(png[at..at + 4].try_into().unwrap());
        // As large as the SVG says it is.
        let root = &svg[svg.find("<svg").unwrap()..];
        let attr = |k: &str| -> u32 { number_after(root, &format!("{k}=\"")) as u32 };
        assert_eq!(
            (size(16), size(20)),
            (attr("width"), attr("height")),
            "{name}.png"
        );
        // The page holds the figure inline: its polylines, word for word.
        let first = svg.find("<polyline").or_else(|| svg.find("<rect")).unwrap();
        let piece = &svg[first..first + svg[first..].find("/>").unwrap()];
        assert!(html.contains(piece), "{name} not in the page");
        svgs.insert(name, svg);
    }
    assert_eq!(html.matches("<svg").count(), PLOTS.len());
    assert_eq!(html.matches("<figcaption>").count(), PLOTS.len());

    // Numbers: psd_map.json read here as plain JSON.
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&map_path).unwrap()).unwrap();
    let fit = &file["fit"];
    let cv = fit["cv_rms_um"].as_f64().unwrap();
    let printed = number_after(&html, "Cross-validated RMS error: ");
    assert!((printed - cv).abs() <= 5e-4 + 1e-12, "{printed} vs {cv}");
    let candidates = fit["candidates"].as_array().unwrap();
    assert!(candidates.len() > 5, "auto tries many models");
    let chosen = file["model"].as_str().unwrap();
    for c in candidates {
        let model = c["model"].as_str().unwrap();
        let row = format!(
            "<td>{model}</td><td>{}</td><td>{:.3}</td><td>{}</td>",
            psdcal_model::stages::MapBasis::parse(model)
                .unwrap()
                .terms(),
            c["cv_rms_um"].as_f64().unwrap(),
            if model == chosen { "chosen" } else { "" }
        );
        assert!(html.contains(&row), "no row {row}");
    }
    // The two outliers are rejected, named by line, and drawn apart.
    let lines: Vec<u64> = fit["rejected_lines"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(lines, OUTLIER_LINES.map(|l| l as u64));
    assert!(html.contains("scan lines 100, 201"));
    assert!(svgs["psd_map_scan_points"].contains("rejected (2)"));

    // The residual arrows: one per kept point, each as long as the file's
    // residual × the scale printed in the title, to the pixel rounding.
    let r = &file["residuals"];
    let column = |k: &str| -> Vec<f64> {
        r[k].as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let (x, y, dx, dy) = (
        column("x_mm"),
        column("y_mm"),
        column("dx_um"),
        column("dy_um"),
    );
    let rejected: Vec<usize> = r["rejected"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    assert_eq!(rejected, OUTLIER_LINES.map(|l| l - 2));
    let kept: Vec<usize> = (0..x.len()).filter(|i| !rejected.contains(i)).collect();
    let svg = &svgs["psd_map_residuals"];
    let scale = number_after(svg, "Scan residuals × ");
    let shafts: Vec<((f64, f64), (f64, f64))> = polylines(svg)
        .into_iter()
        .filter(|(tag, p)| p.len() == 2 && !tag.contains("#000000"))
        .map(|(_, p)| (p[0], p[1]))
        .collect();
    assert_eq!(shafts.len(), kept.len());
    let extent = |v: &mut dyn Iterator<Item = f64>| {
        v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(t), b.max(t))
        })
    };
    let (px0, px1) = extent(&mut shafts.iter().map(|s| s.0 .0));
    let (py0, py1) = extent(&mut shafts.iter().map(|s| s.0 .1));
    let (x0, x1) = extent(&mut kept.iter().map(|&i| x[i]));
    let (y0, y1) = extent(&mut kept.iter().map(|&i| y[i]));
    // Pixels grow to the right and downwards.
    let (sx, sy) = ((x1 - x0) / (px1 - px0), (y1 - y0) / (py1 - py0));
    let mut longest: f64 = 0.0;
    for (a, b) in &shafts {
        let at = (x0 + (a.0 - px0) * sx, y1 - (a.1 - py0) * sy);
        let i = *kept
            .iter()
            .min_by(|&&i, &&j| {
                let d = |k: usize| (x[k] - at.0).hypot(y[k] - at.1);
                d(i).total_cmp(&d(j))
            })
            .unwrap();
        assert!((x[i] - at.0).hypot(y[i] - at.1) < 2.0 * sx.max(sy));
        // The drawn arrow in µm of residual, per axis.
        let drawn = (
            (b.0 - a.0) * sx * 1e3 / scale,
            -(b.1 - a.1) * sy * 1e3 / scale,
        );
        let tolerance = 1.5 * sx.max(sy) * 1e3 / scale;
        assert!(
            (drawn.0 - dx[i]).abs() <= tolerance && (drawn.1 - dy[i]).abs() <= tolerance,
            "point {i}: drawn {drawn:?} µm, file ({}, {}) µm ± {tolerance}",
            dx[i],
            dy[i]
        );
        longest = longest.max(dx[i].hypot(dy[i]));
    }
    // The arrows are readable: the longest spans several pixels.
    assert!(longest * scale * 1e-3 / sx.max(sy) > 5.0);

    // The worst cell's RMS, recomputed from the file over the stage's frame.
    let frame: Vec<f64> = file["stage"]["frame_mm"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let n = SCAN_SUMMARY_CELLS;
    let mut cells = vec![(0usize, 0.0f64); n * n];
    let cell = |t: f64| ((t * n as f64).floor().max(0.0) as usize).min(n - 1);
    for &i in &kept {
        let c = cell((x[i] - frame[0]) / (frame[2] - frame[0]))
            + n * cell((y[i] - frame[1]) / (frame[3] - frame[1]));
        cells[c].0 += 1;
        cells[c].1 += dx[i] * dx[i] + dy[i] * dy[i];
    }
    let worst = cells
        .iter()
        .filter(|c| c.0 > 0)
        .map(|c| (c.1 / c.0 as f64).sqrt())
        .fold(0.0, f64::max);
    let shown = number_after(&html, "RMS residual per cell of a 10 × 10 grid, largest ");
    assert!((shown - worst).abs() <= 5e-3 * worst, "{shown} vs {worst}");
    // With the outliers out, the worst cell is noise-sized, not 40 µm.
    assert!(worst < 3.0, "{worst}");
}

#[test]
fn a_report_that_would_overwrite_an_input_or_the_map_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("report");
    std::fs::create_dir(&report).unwrap();
    // The scan where the report would put a figure.
    let scan = report.join("psd_map_residuals.svg");
    write_scan(&scan);
    let before = std::fs::read(&scan).unwrap();
    let map_path = dir.path().join("psd_map.json");
    let outcome = psd_map_from_scan(&request(&scan, &report)).unwrap();
    let err = outcome.write(&map_path).unwrap_err().to_string();
    assert!(
        err.contains("--report") && err.contains("--scan") && err.contains("psd_map_residuals.svg"),
        "{err}"
    );
    assert_eq!(std::fs::read(&scan).unwrap(), before);
    assert!(!map_path.exists(), "nothing written");
    assert!(!report.join(PSD_MAP_PAGE).exists());
    // psd_map.json where the page would go.
    let scan = dir.path().join("scan.csv");
    write_scan(&scan);
    let page = report.join(PSD_MAP_PAGE);
    let outcome = psd_map_from_scan(&request(&scan, &report)).unwrap();
    let err = outcome.write(&page).unwrap_err().to_string();
    assert!(err.contains("--out") && err.contains("--report"), "{err}");
    assert!(!page.exists());
    // A report folder that is a file: refused before psd_map.json is written.
    let not_a_folder = dir.path().join("file");
    std::fs::write(&not_a_folder, "x").unwrap();
    let outcome = psd_map_from_scan(&request(&scan, &not_a_folder)).unwrap();
    let err = outcome.write(&map_path).unwrap_err().to_string();
    assert!(err.contains("report folder"), "{err}");
    assert!(!map_path.exists());
}
