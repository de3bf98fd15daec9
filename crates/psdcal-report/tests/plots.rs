//! Every plot renders from synthetic data; its SVG holds the axes, the
//! labels (escaped) and one data mark per datum.

use psdcal_report::*;
use psdcal_testkit::svg::polylines;

fn count(svg: &str, tag: &str) -> usize {
    svg.matches(tag).count()
}

fn spiral(n: usize, scale: f64) -> Vec<(f64, f64)> {
    (0..n)
        .map(|k| {
            let t = k as f64 * 0.3;
            (scale * t.cos() * t / 10.0, scale * t.sin() * t / 10.0)
        })
        .collect()
}

fn assert_axes(svg: &str, frame: &Frame) {
    assert!(svg.starts_with("<svg"), "{}", &svg[..80.min(svg.len())]);
    assert!(svg.contains(&escape_html(&frame.title)), "title");
    assert!(svg.contains(&escape_html(&frame.x_label)), "x label");
    assert!(svg.contains(&escape_html(&frame.y_label)), "y label");
    assert!(count(svg, "<text") > 6, "tick labels");
}

#[test]
fn coverage_has_one_circle_per_point_and_escaped_labels() {
    let images: Vec<PointSet> = (0..3)
        .map(|k| PointSet {
            label: format!("img<{k}>&'"),
            points: spiral(10 + k, 4.0),
        })
        .collect();
    let frame = Frame::sensor("Coverage of <sensor> & co", 9.0, 9.0);
    let svg = coverage_svg(&images, 9.0, 9.0, &frame).unwrap();
    assert_axes(&svg, &frame);
    assert_eq!(count(&svg, "<circle"), 10 + 11 + 12);
    assert!(svg.contains("img&lt;2&gt;&amp;&apos;"));
    assert!(!svg.contains("img<"));
}

#[test]
fn residuals_have_one_arrow_head_per_residual() {
    let sets: Vec<ArrowSet> = (0..2)
        .map(|k| ArrowSet {
            label: format!("image {k}"),
            arrows: spiral(7, 100.0)
                .into_iter()
                .map(|p| Arrow {
                    at: p,
                    delta: (0.01 * (k as f64 + 1.0), -0.02),
                })
                .collect(),
        })
        .collect();
    let frame = Frame::fit(
        "Template-plane residuals ×1000",
        "X (mm)",
        "Y (mm)",
        spiral(7, 100.0),
    );
    let svg = residuals_svg(&sets, 1000.0, &frame).unwrap();
    assert_axes(&svg, &frame);
    assert_eq!(count(&svg, "<polygon"), 14);
    assert!(svg.contains("image 1"));
    assert!(residuals_svg(&sets, 0.0, &frame).is_err());
}

#[test]
fn distortion_field_and_spiral() {
    let arrows: Vec<Arrow> = (0..25)
        .map(|k| {
            let (x, y) = ((k % 5) as f64 - 2.0, (k / 5) as f64 - 2.0);
            Arrow {
                at: (x, y),
                delta: (0.01 * x, 0.01 * y),
            }
        })
        .collect();
    let frame = Frame::sensor("Distortion field ×20", 9.0, 9.0);
    let svg = distortion_field_svg(&arrows, 20.0, &[], &frame).unwrap();
    assert_axes(&svg, &frame);
    assert_eq!(count(&svg, "<polygon"), 25);

    let measured = spiral(40, 3.0);
    let corrected: Vec<_> = measured.iter().map(|p| (p.0 * 1.02, p.1 * 1.02)).collect();
    let frame = Frame::sensor("Spiral", 9.0, 9.0);
    let svg = spiral_svg(&measured, &corrected, &frame).unwrap();
    assert_axes(&svg, &frame);
    assert_eq!(count(&svg, "<circle"), 40);
    let empty = spiral_svg(&[], &[], &frame).unwrap();
    assert_eq!(count(&svg, "<polyline") - count(&empty, "<polyline"), 2);
    assert!(svg.contains("measured") && svg.contains("corrected"));
}

#[test]
fn heat_map_has_one_rect_per_cell_plus_the_colour_bar() {
    let cells = |n: usize| -> Vec<HeatCell> {
        (0..n * n)
            .map(|k| HeatCell {
                x: (k % n) as f64,
                y: (k / n) as f64,
                value: k as f64,
            })
            .collect()
    };
    let frame = Frame::new("AoA error", "x (mm)", "y (mm)", (-1.0, 6.0), (-1.0, 6.0));
    let small = heat_map_svg(&cells(3), (1.0, 1.0), &frame, "deg").unwrap();
    let large = heat_map_svg(&cells(5), (1.0, 1.0), &frame, "deg").unwrap();
    assert_axes(&large, &frame);
    assert_eq!(count(&large, "<rect") - count(&small, "<rect"), 25 - 9);
    assert!(count(&small, "<rect") >= 9 + COLORBAR_STEPS);
    assert!(large.contains(">\ndeg\n</text>"));
    assert!(heat_map_svg(&[], (1.0, 1.0), &frame, "deg").is_err());
    assert_eq!(grid_step([0.0, 0.5, 1.0, 0.5]), 0.5);
}

#[test]
fn sensitivity_curves_follow_p40_p41() {
    let [dx, df] = paper_sensitivity_curves(8.0, 4.5, 11);
    assert_eq!(dx.points.len(), 11);
    // At x = 0: 1/f rad per mm, and no sensitivity to f.
    assert!((dx.points[5].1 - (1.0f64 / 8.0).to_degrees()).abs() < 1e-12);
    assert!(df.points[5].1.abs() < 1e-12);
    let svg = aoa_sensitivity_svg(8.0, 4.5).unwrap();
    assert!(svg.contains("AoA sensitivity"));
    assert!(svg.contains("x (mm)") && svg.contains("deg per mm"));
    let frame = Frame::new("t", "x (mm)", "y", (-5.0, 5.0), (0.0, 10.0));
    let none = line_plot_svg(&[], &frame).unwrap();
    let two = line_plot_svg(&[dx, df], &frame).unwrap();
    assert_eq!(count(&two, "<polyline") - count(&none, "<polyline"), 2);
}

#[test]
fn histogram_has_one_bar_per_non_empty_bin_and_the_truth() {
    let values: Vec<f64> = (0..100)
        .map(|k| 8.0 + 0.001 * ((k * 37) % 50) as f64)
        .collect();
    let counts = bin_counts(&values, 10, 8.0, 8.049);
    assert_eq!(counts.iter().sum::<usize>(), 100);
    let svg = histogram_svg(&values, Some(8.02), 10, "f <lens 2>", "f (mm)").unwrap();
    let no_truth = histogram_svg(&values, None, 10, "f", "f (mm)").unwrap();
    assert!(svg.contains("f &lt;lens 2&gt;") && svg.contains("f (mm)") && svg.contains("trials"));
    // The truth is one red line, explained by the caption: no legend.
    assert_eq!(count(&svg, "<polyline") - count(&no_truth, "<polyline"), 1);
    assert!(svg.contains("stroke=\"#D62728\""));
    assert!(!svg.contains("truth"));
    let bars = bin_counts(&values, 10, 8.0, 8.049)
        .iter()
        .filter(|n| **n > 0)
        .count();
    assert_eq!(bars, 10);
    // Bars and the background.
    assert_eq!(count(&no_truth, "<rect"), 1 + bars);
    assert_eq!(count(&svg, "<rect"), 1 + bars);
    assert!(histogram_svg(&[], None, 10, "f", "f").is_err());
    assert!(histogram_svg(&[f64::NAN], None, 10, "f", "f").is_err());
}

#[test]
fn png_variants_write_files() {
    let dir = tempfile::tempdir().unwrap();
    let frame = Frame::sensor("Coverage", 9.0, 9.0);
    let images = [PointSet {
        label: "a".into(),
        points: spiral(20, 4.0),
    }];
    let path = dir.path().join("coverage.png");
    coverage_png(&images, 9.0, 9.0, &frame, &path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let path = dir.path().join("hist.png");
    histogram_png(&[1.0, 2.0, 2.5], Some(2.0), 5, "h", "x", &path).unwrap();
    assert!(std::fs::metadata(&path).unwrap().len() > 1000);
}

/// Every labelled set gets a colour swatch beside its label, right of the
/// plotting area (the points are circles, so a filled rectangle of a set's
/// colour can only be its swatch). Plotters' own series legend placed there
/// had its swatches clipped away.
#[test]
fn legend_swatches_are_drawn_beside_the_data() {
    let frame = Frame::sensor("Coverage", 9.0, 9.0);
    let sets = vec![
        PointSet {
            label: "first".into(),
            points: vec![(0.0, 0.0), (1.0, 1.0)],
        },
        PointSet {
            label: "second".into(),
            points: vec![(-1.0, 2.0)],
        },
    ];
    let svg = coverage_svg(&sets, 9.0, 9.0, &frame).unwrap();
    // The palette's first two colours.
    for fill in ["#1F77B4", "#FF7F0E"] {
        let swatches = svg
            .lines()
            .filter(|l| l.contains("<rect") && l.to_uppercase().contains(fill))
            .count();
        assert_eq!(swatches, 1, "{fill}: {swatches} swatches");
    }
    assert!(svg.contains("first") && svg.contains("second"));
}

#[test]
fn distortion_field_draws_the_valid_region_boundary() {
    // Two arrows at known points give the data → pixel map of each axis
    // (an arrow's shaft, in the field's colour, starts at its point); the boundary, a circle of
    // radius 3 mm about (0.5, −0.7) in 90 rays and closed, must come back
    // from its pixels at that radius, to the pixel rounding.
    let arrows = [
        Arrow {
            at: (-4.0, -4.0),
            delta: (0.1, 0.0),
        },
        Arrow {
            at: (4.0, 4.0),
            delta: (0.1, 0.0),
        },
    ];
    let (centre, radius) = ((0.5, -0.7), 3.0);
    let circle: Vec<(f64, f64)> = (0..=90)
        .map(|i| {
            let t = std::f64::consts::TAU * (i % 90) as f64 / 90.0;
            (centre.0 + radius * t.cos(), centre.1 + radius * t.sin())
        })
        .collect();
    let frame = Frame::sensor("Distortion field", 9.0, 9.0);
    let plain = distortion_field_svg(&arrows, 1.0, &[], &frame).unwrap();
    let svg = distortion_field_svg(&arrows, 1.0, std::slice::from_ref(&circle), &frame).unwrap();
    assert!(svg.contains(OUTLINE_LABEL) && !plain.contains(OUTLINE_LABEL));
    let lines = polylines(&svg);
    assert_eq!(lines.len(), polylines(&plain).len() + 1);
    let shafts: Vec<(f64, f64)> = lines
        .iter()
        .filter(|(tag, p)| p.len() == 2 && !tag.contains("#000000"))
        .map(|(_, p)| p[0])
        .collect();
    let (a, b) = (
        shafts.iter().find(|p| p.0 < 300.0).copied().unwrap(),
        shafts.iter().find(|p| p.0 > 300.0).copied().unwrap(),
    );
    let to_mm = |p: (f64, f64)| {
        (
            -4.0 + 8.0 * (p.0 - a.0) / (b.0 - a.0),
            -4.0 + 8.0 * (p.1 - a.1) / (b.1 - a.1),
        )
    };
    let mm_per_px = 8.0 / (b.0 - a.0).abs().min((b.1 - a.1).abs());
    let (tag, outline) = lines
        .iter()
        .find(|(_, p)| p.len() == circle.len())
        .expect("the boundary's polyline");
    assert!(tag.contains("stroke=\"#000000\""), "{tag}");
    for &p in outline {
        let q = to_mm(p);
        let r = (q.0 - centre.0).hypot(q.1 - centre.1);
        assert!((r - radius).abs() <= 2.0 * mm_per_px, "{q:?} at {r} mm");
    }
    // Non-finite boundary points are refused like any other datum.
    assert!(
        distortion_field_svg(&arrows, 1.0, &[vec![(0.0, 0.0), (f64::NAN, 1.0)]], &frame).is_err()
    );
}
