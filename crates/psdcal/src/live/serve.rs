//! `psdcal serve`: the rig's positions live over HTTP (docs/formats.md,
//! "Live positions"; `tiny_http`, one thread per viewer).
//!
//! - `GET /`: one self-contained page (psdcal-report's `live_page`);
//! - `GET /rig`: the rig as JSON (`sensors`: `id`, `t_mm`, `rvec`, the
//!   world-frame optical axis `axis`, the half field of view
//!   `half_fov_rad` from the active area and the focal length);
//! - `GET /stream`: Server-Sent Events: first `event: start` (`unix_s` the
//!   wall time of the stream's first sample, `sample_rate_hz`, `window_s`,
//!   `leds`), then per window and LED one `data:` JSON object (`t_s`, `led`,
//!   `x_world_mm`, `y_world_mm`, `z_world_mm`, `cov_world_mm2` [xx, xy, xz,
//!   yy, yz, zz], `sensors`, `snr_db`, `status`, `per_sensor` [{`id`,
//!   `snr_db`, `status`}], and `vx_mm_s`, `vy_mm_s`, `vz_mm_s` with a
//!   filter; absent numbers are `null`), and `event: end` when the input is
//!   done: a viewer stops there (tiny_http keeps an HTTP/1.1 connection
//!   asked without `Connection: close` open for a next request). The same
//!   rows as `track`'s: the same windows, filter and numbers.
//!
//! A viewer connecting late receives the last [`HISTORY`] events first.
//! With `--realtime` a recording is replayed at its sample rate, from the
//! moment the first viewer opens `/stream` (so that a demo starts when it is
//! watched); each window's events are sent as soon as its last sample is
//! read. When the input ends the streams are closed and `serve` returns.

use std::collections::VecDeque;
use std::io::{BufRead, Write};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime};

use psdcal_io::Sample;
use psdcal_signal::Window;
use serde_json::{json, Value};

use crate::base::error::{Error, Result};
use crate::signals::track::{prepare, Answerer, Prepared, TrackRequest};
use crate::signals::track_rig::{LedFilters, LedFix};

/// Events kept for a viewer connecting late.
pub const HISTORY: usize = 4000;

/// What `serve` needs.
#[derive(Debug, Clone, PartialEq)]
pub struct ServeRequest {
    /// The stream: a rig (`TrackTarget::Rig`), its tones, samples, filter.
    pub track: TrackRequest,
    /// Replay a recording at its sample rate.
    pub realtime: bool,
    /// Address to bind, e.g. `127.0.0.1:8080` (port 0: any free port).
    pub bind: String,
}

/// What `serve` did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ServeSummary {
    /// Samples read.
    pub samples: u64,
    /// Windows answered.
    pub windows: u64,
}

/// The viewers' channels and the recent events.
#[derive(Default)]
struct Hub {
    viewers: Vec<Sender<Option<String>>>,
    history: VecDeque<String>,
    start: Option<String>,
    /// Set when the first viewer opens /stream.
    watched: bool,
}

impl Hub {
    /// Sends `event` to every viewer (dropping those gone) and keeps it.
    fn publish(&mut self, event: String) {
        self.viewers.retain(|v| v.send(Some(event.clone())).is_ok());
        self.history.push_back(event);
        if self.history.len() > HISTORY {
            self.history.pop_front();
        }
    }
}

/// Serves the rig's positions (module documentation); `listening` is
/// called with the bound address before the first sample is read.
///
/// Errors: those of `track` (the rig, tones, samples), an address that
/// cannot be bound, a target that is not a rig.
pub fn serve(
    request: &ServeRequest,
    input: impl BufRead,
    listening: impl FnOnce(&str),
) -> Result<ServeSummary> {
    let Prepared {
        answerer,
        tones,
        mut source,
        fs,
        mut windows,
    } = prepare(&request.track, input)?;
    let Answerer::Rig(rig) = answerer else {
        return Err(Error::Options(
            "serve shows a rig's positions; expected --rig FILE".to_string(),
        ));
    };
    let server = tiny_http::Server::http(&request.bind).map_err(|e| {
        Error::Options(format!(
            "cannot listen on {}: {e}; expected a free address (--bind, --port)",
            request.bind
        ))
    })?;
    let address = server
        .server_addr()
        .to_ip()
        .map_or_else(|| request.bind.clone(), |a| a.to_string());
    let rig_json = crate::live::rig_json::rig_json(rig.rig()).to_string();
    let hub = Arc::new(Mutex::new(Hub::default()));
    let server = Arc::new(server);
    let http = {
        let (server, hub, rig_json) = (server.clone(), hub.clone(), rig_json.clone());
        std::thread::spawn(move || answer_requests(&server, &hub, &rig_json))
    };
    listening(&address);
    if request.realtime && request.track.raw.is_some() {
        while !hub.lock().map(|h| h.watched).unwrap_or(true) {
            std::thread::sleep(Duration::from_millis(20));
        }
    }
    let leds: Vec<&str> = tones.tones.iter().map(|t| t.led.as_str()).collect();
    let started = Instant::now();
    let unix = SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64());
    let start = json!({"unix_s": unix, "sample_rate_hz": fs, "window_s": request.track.window_s,
        "leds": leds, "filter": request.track.filter.name()});
    if let Ok(mut h) = hub.lock() {
        let event = format!("event: start\ndata: {start}\n\n");
        h.start = Some(event.clone());
        h.viewers.retain(|v| v.send(Some(event.clone())).is_ok());
    }
    let mut filters = LedFilters::new(&request.track.filter, tones.tones.len());
    let ids = rig.ids();
    let mut summary = ServeSummary::default();
    let realtime = request.realtime && request.track.raw.is_some();
    let input_error = |e| crate::signals::track::stream_error(e);
    while let Some(sample) = source.next_sample().map_err(input_error)? {
        let Sample::Values(values) = sample else {
            continue;
        };
        summary.samples += 1;
        // Paced every 64 samples and at each window's last sample, which is
        // then read no earlier than due.
        let last_of_window = windows.pending() + 1 == windows.window_len();
        if realtime && (summary.samples % 64 == 0 || last_of_window) {
            let due = Duration::from_secs_f64(summary.samples as f64 / fs);
            if let Some(wait) = due.checked_sub(started.elapsed()) {
                std::thread::sleep(wait);
            }
        }
        if let Some(Window { t0_s, estimates }) = windows.push(&values) {
            let mut fixes = rig.fixes(&tones, &estimates);
            filters.apply(t0_s, &mut fixes);
            if let Ok(mut h) = hub.lock() {
                for fix in &fixes {
                    h.publish(format!("data: {}\n\n", event_json(t0_s, fix, &ids)));
                }
            }
            summary.windows += 1;
        }
    }
    // The end: every viewer gets `end`, its stream closes; wait for them.
    let viewers = {
        let mut h = hub
            .lock()
            .map_err(|_| Error::Input("a viewer thread failed".to_string()))?;
        h.publish("event: end\ndata: {}\n\n".to_string());
        for v in &h.viewers {
            let _ = v.send(None);
        }
        std::mem::take(&mut h.viewers).len()
    };
    let _ = viewers;
    server.unblock();
    let _ = http.join();
    Ok(summary)
}

/// One window's event of one LED (module documentation).
fn event_json(t0: f64, fix: &LedFix, ids: &[String]) -> Value {
    let finite = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
    let (p, c) = match &fix.position {
        Some((p, c)) => (
            [finite(p.x), finite(p.y), finite(p.z)],
            json!([
                c[(0, 0)],
                c[(0, 1)],
                c[(0, 2)],
                c[(1, 1)],
                c[(1, 2)],
                c[(2, 2)]
            ]),
        ),
        None => ([Value::Null, Value::Null, Value::Null], Value::Null),
    };
    let per_sensor: Vec<Value> = ids
        .iter()
        .zip(&fix.per_sensor)
        .map(|(id, (snr, status))| json!({"id": id, "snr_db": snr.map_or(Value::Null, finite), "status": status}))
        .collect();
    let mut event = json!({
        "t_s": t0, "led": fix.led, "x_world_mm": p[0], "y_world_mm": p[1], "z_world_mm": p[2],
        "cov_world_mm2": c, "sensors": fix.sensors, "snr_db": fix.snr_db.map_or(Value::Null, finite),
        "status": fix.status, "per_sensor": per_sensor,
    });
    if let Some(v) = &fix.velocity {
        event["vx_mm_s"] = finite(v.x);
        event["vy_mm_s"] = finite(v.y);
        event["vz_mm_s"] = finite(v.z);
    }
    event
}

/// Answers HTTP requests until the server is unblocked.
fn answer_requests(server: &tiny_http::Server, hub: &Arc<Mutex<Hub>>, rig_json: &str) {
    let mut streams = Vec::new();
    for request in server.incoming_requests() {
        let path = request.url().split('?').next().unwrap_or("").to_string();
        let header = |v: &str| {
            tiny_http::Header::from_bytes(&b"Content-Type"[..], v.as_bytes()).unwrap_or_else(|()| {
                tiny_http::Header::from_bytes(&b"X"[..], &b"x"[..])
                    .unwrap_or_else(|()| unreachable!())
            })
        };
        let answered = match path.as_str() {
            "/" | "/index.html" => request.respond(
                tiny_http::Response::from_string(psdcal_report::live_page())
                    .with_header(header("text/html; charset=utf-8")),
            ),
            "/rig" => request.respond(
                tiny_http::Response::from_string(rig_json).with_header(header("application/json")),
            ),
            "/stream" => {
                let (tx, rx) = channel();
                if let Ok(mut h) = hub.lock() {
                    for event in h.start.iter().chain(h.history.iter()) {
                        let _ = tx.send(Some(event.clone()));
                    }
                    h.viewers.push(tx);
                    h.watched = true;
                }
                let writer = request.into_writer();
                streams.push(std::thread::spawn(move || stream_events(writer, rx)));
                Ok(())
            }
            _ => {
                request.respond(tiny_http::Response::from_string("not found").with_status_code(404))
            }
        };
        let _ = answered;
    }
    for s in streams {
        let _ = s.join();
    }
}

/// Writes the SSE response: the header, then each event as it comes, until
/// the end (`None`) or the viewer leaves.
fn stream_events(mut w: Box<dyn Write + Send>, rx: Receiver<Option<String>>) {
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-cache\r\n\
                Connection: close\r\nAccess-Control-Allow-Origin: *\r\n\r\n";
    if w.write_all(head.as_bytes())
        .and_then(|()| w.flush())
        .is_err()
    {
        return;
    }
    while let Ok(Some(event)) = rx.recv() {
        // Every event still queued goes out in one write.
        let mut text = event;
        let mut end = false;
        while let Ok(next) = rx.try_recv() {
            match next {
                Some(e) => text += &e,
                None => {
                    end = true;
                    break;
                }
            }
        }
        if w.write_all(text.as_bytes())
            .and_then(|()| w.flush())
            .is_err()
            || end
        {
            return;
        }
    }
}
