//! `serve` streams the rows `track` writes: on a short simulated recording
//! of moving LEDs, every window reaches a viewer of `/stream` as JSON with
//! the same positions, covariances and velocities as `track --filter cv`,
//! `/rig` names every sensor, `/` is one page fetching nothing from another
//! host, and `serve` returns when the input ends.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;

use psdcal::{
    simulate_moving, DemodConfig, Lens, MovingRequest, ServeRequest, TrackFilter, TrackRequest,
    TrackTarget, DEFAULT_MOVING_NOISE_V,
};

fn get(address: &str, path: &str) -> String {
    let mut s = TcpStream::connect(address).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {address}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    text
}

/// The lines of `/stream` up to the `end` event's data line. The viewer
/// stops there, as the page does: an HTTP/1.1 connection asked without
/// `Connection: close` stays open for a next request after the stream's
/// response (tiny_http keeps it), so reading to the end of the connection
/// would wait for the process to exit.
fn stream_lines(address: &str) -> Vec<String> {
    let mut s = TcpStream::connect(address).unwrap();
    write!(s, "GET /stream HTTP/1.1\r\nHost: {address}\r\n\r\n").unwrap();
    let mut lines = Vec::new();
    let mut ended = false;
    for line in BufReader::new(s).lines() {
        let line = line.unwrap();
        let done = ended && line.starts_with("data:");
        ended |= line == "event: end";
        lines.push(line);
        if done {
            break;
        }
    }
    lines
}

#[test]
fn the_stream_carries_the_rows_of_track() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulate_moving(&MovingRequest {
        lens: Lens::Two,
        calibration_snr_db: Some(60.0),
        images: 9,
        duration_s: 1.0,
        noise_v: DEFAULT_MOVING_NOISE_V,
        seed: 4,
        out: d.to_path_buf(),
        force: false,
    })
    .unwrap();
    let track = TrackRequest {
        target: TrackTarget::Rig(d.join("rig.json")),
        rate_hz: None,
        tones: d.join("tones.csv"),
        window_s: 0.05,
        config: DemodConfig::default(),
        raw: Some(d.join("raw.tdms")),
        channels: Vec::new(),
        limits: Default::default(),
        filter: TrackFilter::from_name("cv", None).unwrap(),
    };
    let mut csv = Vec::new();
    psdcal::track(&track, "".as_bytes(), &mut csv).unwrap();
    let rows: Vec<Vec<String>> = String::from_utf8(csv)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    assert_eq!(rows.len(), 40);
    let request = ServeRequest {
        track,
        realtime: true,
        bind: "127.0.0.1:0".to_string(),
    };
    let mut viewer = None;
    let summary = psdcal::serve(&request, "".as_bytes(), |address| {
        let address = address.to_string();
        viewer = Some(std::thread::spawn(move || {
            let rig = get(&address, "/rig");
            let page = get(&address, "/");
            let lines = stream_lines(&address);
            (rig, page, lines)
        }));
    })
    .unwrap();
    assert_eq!(summary.windows, 20);
    let (rig, page, lines) = viewer.unwrap().join().unwrap();
    for id in ["s1", "s2", "s3", "s4"] {
        assert!(rig.contains(&format!("\"id\":\"{id}\"")), "{rig}");
    }
    assert!(page.contains("text/html") && page.contains("<canvas"));
    assert!(!page.contains("http://") && !page.contains("https://") && !page.contains("//cdn"));
    assert!(
        lines[0].starts_with("HTTP/1.1 200")
            && lines.iter().any(|l| l == "Content-Type: text/event-stream")
    );
    assert!(lines.iter().any(|l| l == "event: start") && lines.iter().any(|l| l == "event: end"));
    let events: Vec<serde_json::Value> = lines
        .iter()
        .filter_map(|l| l.strip_prefix("data: "))
        .map(|l| serde_json::from_str(l).unwrap())
        .filter(|v: &serde_json::Value| v.get("led").is_some())
        .collect();
    assert_eq!(events.len(), rows.len());
    let close = |a: f64, text: &str| {
        let b: f64 = text.parse().unwrap();
        (a - b).abs() <= 1e-9 * (1.0 + b.abs())
    };
    for (e, row) in events.iter().zip(&rows) {
        assert!(close(e["t_s"].as_f64().unwrap(), &row[0]));
        assert_eq!(e["led"], row[1].as_str());
        assert_eq!(e["status"], row[14].as_str());
        for (k, col) in [
            ("x_world_mm", 3),
            ("y_world_mm", 4),
            ("z_world_mm", 5),
            ("vx_mm_s", 15),
        ] {
            assert!(
                close(e[k].as_f64().unwrap(), &row[col]),
                "{k}: {e} vs {row:?}"
            );
        }
        let c = e["cov_world_mm2"].as_array().unwrap();
        assert!(close(c[0].as_f64().unwrap().sqrt(), &row[6]));
        assert!(close(c[1].as_f64().unwrap(), &row[9]));
        assert_eq!(e["per_sensor"].as_array().unwrap().len(), 4);
    }
}
