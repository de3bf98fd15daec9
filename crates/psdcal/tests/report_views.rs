//! The calibration report's views beyond the fit (issues 14 and 18): a
//! calibration that carries a PSD map shows its field, its size and its own
//! uncertainty (the size's largest value against the map evaluated here
//! independently through the fitted stage) and its scan's residuals (the
//! stage's stored summary against psd_map.json, recomputed here), and every
//! report with data shows the template poses in 3-D.

use psdcal::{
    calibrate, psd_map_from_scan, report_content, simulate_files, simulate_scan_file, write_report,
    CalibrationOptions, DataSet, DataSetFiles, LoadOptions, LoadedSensor, PointSource, PsdGeometry,
    PsdMapModel, PsdMapRequest, ReportRequest, ScanRequest, SimulateRequest, DEFAULT_RECORD_CYCLES,
};
use psdcal_report::PlotData;
use psdcal_sim::{Lens, TemplateKind};

#[test]
fn a_calibration_with_a_psd_map_reports_the_map_and_the_poses() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("scan.csv");
    simulate_scan_file(&ScanRequest {
        step_mm: 0.5,
        stage_sigma_um: 0.3,
        snr_db: Some(50.0),
        nonlinearity: true,
        geometry: PsdGeometry::default(),
        seed: 7,
        out: scan.clone(),
    })
    .unwrap();
    let fitted = psd_map_from_scan(&PsdMapRequest {
        scan,
        model: PsdMapModel::Auto,
        geometry: PsdGeometry::default(),
        seed: 0,
        command: String::new(),
        report: None,
        limits: Default::default(),
        force: false,
    })
    .unwrap();
    let map_path = dir.path().join("psd_map.json");
    fitted.write(&map_path).unwrap();
    let data = dir.path().join("data");
    simulate_files(&SimulateRequest {
        lens: Lens::Two,
        snr_db: Some(40.0),
        imbalance: false,
        psd_distortion: false,
        psd_nonlinearity: true,
        images: 12,
        template: TemplateKind::Scatter14,
        record_cycles: DEFAULT_RECORD_CYCLES,
        seed: 3,
        out: data.clone(),
        force: false,
    })
    .unwrap();
    let files = DataSetFiles {
        template: data.join("template.csv"),
        points: PointSource::Observations(data.join("observations.csv")),
        gains: None,
    };
    let set = DataSet::from_files(&files, &LoadOptions::default()).unwrap();
    let calibrated = calibrate(
        &set,
        &CalibrationOptions {
            psd_map: Some(map_path.clone()),
            ..CalibrationOptions::default()
        },
    )
    .unwrap();
    let cal = dir.path().join("calibration.json");
    calibrated.write(&set, &cal, None).unwrap();
    let request = ReportRequest {
        calibration: cal.clone(),
        data: Some((data.join("template.csv"), data.join("observations.csv"))),
        out: dir.path().join("report"),
        limits: Default::default(),
        force: false,
    };
    let loaded = LoadedSensor::read(&cal).unwrap();
    let content = report_content(&request, &loaded, Some(&set)).unwrap();
    let names: Vec<&str> = content.plots.iter().map(|p| p.name).collect();
    for name in [
        "psd_map_field",
        "psd_map_magnitude",
        "psd_map_uncertainty",
        "psd_map_scan_residuals",
        "psd_map_scan_rms",
        "template_poses",
    ] {
        assert!(names.contains(&name), "{name} missing from {names:?}");
    }
    scan_summary_matches_the_map_file(&map_path, &cal, &content);
    // The size map's largest value: the fitted stage evaluated here over
    // the same 21 × 21 grid inside the scan's hull.
    let magnitude = content
        .plots
        .iter()
        .find(|p| p.name == "psd_map_magnitude")
        .unwrap();
    let PlotData::HeatMap { cells, .. } = &magnitude.data else {
        panic!("the map's size is a heat map");
    };
    let g = PsdGeometry::default();
    let mut largest: f64 = 0.0;
    for k in 0..21 * 21 {
        let m = nalgebra::Vector2::new(
            g.lx * (-0.5 + (k % 21) as f64 / 20.0),
            g.ly * (-0.5 + (k / 21) as f64 / 20.0),
        );
        if psdcal_model::Stage::contains_input(&fitted.fit.map, &m) {
            largest = largest.max(1e3 * fitted.fit.map.displacement(&fitted.fit.block, &m).norm());
        }
    }
    let got = cells.iter().map(|c| c.value).fold(0.0, f64::max);
    assert!(
        (got - largest).abs() <= 1e-9 * largest,
        "{got} vs {largest}"
    );
    // The simulated non-linearity is about 1 % of the size at the edge:
    // tens of µm, not nothing.
    assert!(largest > 20.0, "{largest}");
    // The poses: one outline per image, each as many corners as the hull
    // of the template's LEDs, in front of the sensor.
    let poses = content
        .plots
        .iter()
        .find(|p| p.name == "template_poses")
        .unwrap();
    let PlotData::Poses { poses, .. } = &poses.data else {
        panic!("the poses are a 3-D view");
    };
    assert_eq!(poses.len(), 12);
    for p in poses {
        assert_eq!(p.leds.len(), set.template.leds.len());
        assert!(p.leds.iter().all(|l| l[2] > 0.0), "in front of the sensor");
    }
    let written = write_report(&request).unwrap();
    assert!(written.plots.contains(&"psd_map_field"));
    let html = std::fs::read_to_string(written.html).unwrap();
    assert!(html.contains("PSD map") && !html.contains("<script"));
}

/// calibration.json's `scan` summary of the map's stage against psd_map.json
/// read here as plain JSON: the same fit, and the residuals per cell
/// recomputed (outliers left out, 10 × 10 cells of the stage's frame); the
/// report's RMS heat map shows those cells, its list the CV RMS.
fn scan_summary_matches_the_map_file(
    map_path: &std::path::Path,
    cal: &std::path::Path,
    content: &psdcal_report::CalibrationReport,
) {
    let read = |p: &std::path::Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    let (map, cal) = (read(map_path), read(cal));
    let stage = cal["stages"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["kind"] == "psd_map")
        .unwrap();
    let scan = &stage["scan"];
    assert_eq!(scan["fit"], map["fit"]);
    assert_eq!(scan["model"], map["model"]);
    let column = |v: &serde_json::Value, k: &str| -> Vec<f64> {
        v[k].as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let r = &map["residuals"];
    let (x, y, dx, dy) = (
        column(r, "x_mm"),
        column(r, "y_mm"),
        column(r, "dx_um"),
        column(r, "dy_um"),
    );
    let rejected: Vec<usize> = r
        .get("rejected")
        .and_then(|v| v.as_array())
        .map(|a| a.iter().map(|v| v.as_u64().unwrap() as usize).collect())
        .unwrap_or_default();
    let frame = column(&map["stage"], "frame_mm");
    let n = 10usize;
    // Per cell: points, Σ dx, Σ dy, Σ |r|².
    let mut sums = vec![(0usize, 0.0, 0.0, 0.0); n * n];
    let cell = |t: f64| ((t * n as f64).floor().max(0.0) as usize).min(n - 1);
    for i in (0..x.len()).filter(|i| !rejected.contains(i)) {
        let c = cell((x[i] - frame[0]) / (frame[2] - frame[0]))
            + n * cell((y[i] - frame[1]) / (frame[3] - frame[1]));
        let s = &mut sums[c];
        *s = (
            s.0 + 1,
            s.1 + dx[i],
            s.2 + dy[i],
            s.3 + dx[i] * dx[i] + dy[i] * dy[i],
        );
    }
    let expected: Vec<_> = sums.iter().filter(|s| s.0 > 0).collect();
    let cells = &scan["residual_cells"];
    assert_eq!(cells["cells"], 10);
    let (points, mx, my, rms) = (
        cells["points"].as_array().unwrap(),
        column(cells, "dx_um"),
        column(cells, "dy_um"),
        column(cells, "rms_um"),
    );
    assert_eq!(points.len(), expected.len());
    for (k, s) in expected.iter().enumerate() {
        let m = s.0 as f64;
        assert_eq!(points[k].as_u64().unwrap() as usize, s.0);
        assert!((mx[k] - s.1 / m).abs() < 1e-9 && (my[k] - s.2 / m).abs() < 1e-9);
        assert!((rms[k] - (s.3 / m).sqrt()).abs() < 1e-9);
    }
    let heat = content
        .plots
        .iter()
        .find(|p| p.name == "psd_map_scan_rms")
        .unwrap();
    let PlotData::HeatMap { cells, .. } = &heat.data else {
        panic!("the scan's RMS per cell is a heat map");
    };
    let shown: Vec<f64> = cells.iter().map(|c| c.value).collect();
    assert_eq!(shown, rms);
    let cv = format!(
        "cross-validated RMS error {:.3} µm",
        map["fit"]["cv_rms_um"].as_f64().unwrap()
    );
    assert!(
        content.sources.iter().any(|s| s.contains(&cv)),
        "{cv} not in {:?}",
        content.sources
    );
}

/// Issue 12's folding calibration (k1 = −0.02 mm⁻² about (0.5, −0.7): the
/// radial correction's determinant (1 + k1 r²)(1 + 3 k1 r²) first vanishes
/// at r* = 1/√(3 · 0.02) = 4.08 mm, inside the active area in some
/// directions): the distortion field carries the valid region's boundary,
/// every drawn point at r* from the centre and inside the plot, and the
/// drawing holds its legend entry. A calibration that does not fold has
/// none.
#[test]
fn the_distortion_field_draws_the_valid_region_boundary() {
    use psdcal_io::{write_calibration, Calibration, Covariance, StdDevs};
    use psdcal_model::{Param, SensorModel};
    let dir = tempfile::tempdir().unwrap();
    let field = |k1: f64| {
        let mut model = SensorModel::pinhole(8.0, 0.5, -0.7);
        model.distortion.k1 = k1;
        let mut cal = Calibration::from_model(&model, &PsdGeometry::default());
        cal.set_estimated(&[Param::F]);
        cal.std = StdDevs(vec![("f".into(), 0.01)]);
        cal.covariance = Covariance {
            parameters: vec!["f".into()],
            matrix: vec![vec![1e-4]],
        };
        cal.store_valid_region();
        let path = dir.path().join(format!("cal{k1}.json"));
        write_calibration(&path, &cal).unwrap();
        let request = ReportRequest {
            calibration: path.clone(),
            data: None,
            out: dir.path().join("report"),
            limits: Default::default(),
            force: false,
        };
        let loaded = LoadedSensor::read(&path).unwrap();
        let content = report_content(&request, &loaded, None).unwrap();
        content
            .plots
            .into_iter()
            .find(|p| p.name == "distortion_field")
            .expect("a distortion field")
    };
    let plot = field(-0.02);
    let PlotData::DistortionField {
        boundary, frame, ..
    } = &plot.data
    else {
        panic!("not a field: {:?}", plot.data)
    };
    let r_star = 1.0 / (3.0f64 * 0.02).sqrt();
    let points: Vec<(f64, f64)> = boundary.iter().flatten().copied().collect();
    assert!(points.len() >= 20, "{} boundary points", points.len());
    for &(x, y) in &points {
        let r = (x - 0.5).hypot(y + 0.7);
        assert!((r - r_star).abs() <= 1e-6 * r_star, "({x}, {y}) at {r} mm");
        assert!(x >= frame.x_range.0 && x <= frame.x_range.1);
        assert!(y >= frame.y_range.0 && y <= frame.y_range.1);
    }
    let svg = plot.svg().unwrap();
    assert!(svg.contains(psdcal_report::OUTLINE_LABEL));
    assert!(plot.caption.contains("valid region"));
    let plain = field(0.0);
    let PlotData::DistortionField { boundary, .. } = &plain.data else {
        panic!("not a field")
    };
    assert!(boundary.is_empty());
    assert!(!plain.svg().unwrap().contains(psdcal_report::OUTLINE_LABEL));
}
