//! `track`: angles of arrival from a live stream of raw samples
//! (docs/model.md §8.5): CSV rows `vx1,vx2,vy1,vy2` (volts) in, as they
//! arrive; per window of `round(window fs)` samples and per LED of
//! tones.csv, one row `t_s,led,alpha_x_deg,alpha_y_deg,snr_db,status` out,
//! flushed at the end of each window (`daq-reader | psdcal track … |
//! controller`).
//!
//! Each window is demodulated on its own, exactly as `demodulate` treats a
//! record of the same samples (its own filter start, frequency estimate and
//! noise): the same samples give the same angles. `t_s` is the time of the
//! window's first sample, counted from the first sample of the stream.
//!
//! Input lines: blank lines and `#` comments are skipped; a first line
//! naming the columns (`vx1`, `vx2`, `vy1`, `vy2` in any order, extra
//! columns ignored) sets their order, otherwise the first four fields are
//! `vx1,vx2,vy1,vy2`. A line that is not four finite numbers (or longer
//! than 1 MiB, or not UTF-8) gives a row with the status `malformed_line`
//! and is not counted as a sample; the stream goes on. Statuses per LED:
//! `ok`, `dark`, `saturated`, `too_short`, `tone_collision`, or the
//! location code of an angle that cannot be computed (e.g.
//! `outside_valid_region`).

use std::io::{BufRead, Read, Write};
use std::path::PathBuf;

use psdcal_io::{Tones, MAX_LINE_BYTES};
use psdcal_locate::{LocateOptions, Measurement};
use psdcal_model::Amplitudes;
use psdcal_signal::tones::check_separable;
use psdcal_signal::{demodulate_record, DemodConfig, SignalError};

use crate::error::{Error, Result};
use crate::sensor::LoadedSensor;
use crate::table::{deg, num};

/// What `track` needs.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackRequest {
    /// calibration.json.
    pub calibration: PathBuf,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// tones.csv: the LEDs and their tones.
    pub tones: PathBuf,
    /// Window length, s.
    pub window_s: f64,
    /// The demodulation's parameters.
    pub config: DemodConfig,
}

/// What `track` saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TrackSummary {
    /// Samples read.
    pub samples: u64,
    /// Windows answered.
    pub windows: u64,
    /// Malformed lines.
    pub malformed: u64,
}

const HEADER: &str = "t_s,led,alpha_x_deg,alpha_y_deg,snr_db,status";

/// Runs the stream from `input` to `output` until the input ends. See the
/// module documentation.
///
/// Errors: the calibration or tones file, an unusable rate, window or tone
/// set (checked before the first sample), reading the input or writing the
/// output.
pub fn track(
    request: &TrackRequest,
    mut input: impl BufRead,
    mut output: impl Write,
) -> Result<TrackSummary> {
    let sensor = LoadedSensor::read(&request.calibration)?;
    let tones = Tones::read(&request.tones)?;
    let fs = request.rate_hz;
    if !(fs.is_finite() && fs > 0.0) {
        return Err(Error::Options(format!(
            "--rate {fs}: expected a finite, positive sample rate"
        )));
    }
    let window = (request.window_s * fs).round();
    if !(window >= 1.0 && window <= crate::demodulate::MAX_RECORD_SAMPLES as f64) {
        return Err(Error::Options(format!(
            "--window {} s: expected between one sample and {} samples",
            request.window_s,
            crate::demodulate::MAX_RECORD_SAMPLES
        )));
    }
    let window = window as usize;
    let freqs: Vec<f64> = tones.tones.iter().map(|t| t.frequency_hz).collect();
    check_separable(&freqs, fs, window as f64 / fs)
        .map_err(|e| Error::Options(format!("{}: {e}", tones.source)))?;
    request
        .config
        .validate()
        .map_err(|e| Error::Options(e.to_string()))?;
    let mut summary = TrackSummary::default();
    // A reader that went away (`| head`) ends the stream quietly.
    macro_rules! emit {
        ($result:expr) => {
            match $result {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => return Ok(summary),
                Err(source) => {
                    return Err(Error::Io(psdcal_io::IoError::Write {
                        file: "standard output".to_string(),
                        source,
                    }))
                }
            }
        };
    }
    emit!(writeln!(output, "{HEADER}").and_then(|()| output.flush()));
    let mut columns: Option<[usize; 4]> = None;
    let mut first_line = true;
    let mut frames: Vec<[f64; 4]> = Vec::with_capacity(window);
    let mut line = Vec::new();
    let options = LocateOptions::default();
    loop {
        line.clear();
        let read = (&mut input)
            .take(MAX_LINE_BYTES as u64 + 1)
            .read_until(b'\n', &mut line)
            .map_err(|source| {
                Error::Io(psdcal_io::IoError::Read {
                    file: "standard input".to_string(),
                    source,
                })
            })?;
        if read == 0 {
            break;
        }
        let too_long = line.len() > MAX_LINE_BYTES && line.last() != Some(&b'\n');
        if too_long {
            // Skip the rest of the line.
            let mut rest = Vec::new();
            let _ = input.read_until(b'\n', &mut rest);
        }
        let parsed = if too_long {
            None
        } else {
            match std::str::from_utf8(&line) {
                Ok(text) => {
                    let text = text.trim();
                    if text.is_empty() || text.starts_with('#') {
                        continue;
                    }
                    let fields: Vec<&str> = text.split(',').map(str::trim).collect();
                    if first_line && fields.iter().any(|f| f.eq_ignore_ascii_case("vx1")) {
                        first_line = false;
                        columns = header_columns(&fields);
                        if columns.is_none() {
                            return Err(Error::Input(format!(
                                "standard input: the header '{}' lacks one of vx1, vx2, vy1, vy2",
                                text.chars().take(60).collect::<String>()
                            )));
                        }
                        continue;
                    }
                    first_line = false;
                    sample(&fields, columns.unwrap_or([0, 1, 2, 3]))
                }
                Err(_) => None,
            }
        };
        let Some(frame) = parsed else {
            summary.malformed += 1;
            let t = (summary.samples as f64) / fs;
            emit!(writeln!(output, "{},,,,,malformed_line", num(t)).and_then(|()| output.flush()));
            continue;
        };
        frames.push(frame);
        summary.samples += 1;
        if frames.len() == window {
            let t0 = (summary.samples - window as u64) as f64 / fs;
            let estimate = demodulate_record(&frames, fs, &freqs, &request.config);
            for (k, tone) in tones.tones.iter().enumerate() {
                let led = csv_field(&tone.led);
                let row = match &estimate {
                    Ok(est) => {
                        let t = &est.tones[k];
                        let snr = num(t.min_snr_db());
                        if t.dark {
                            format!("{},{led},,,{snr},dark", num(t0))
                        } else {
                            let a = t.amplitudes;
                            let amps = Amplitudes {
                                vx1: a[0],
                                vx2: a[1],
                                vy1: a[2],
                                vy2: a[3],
                            };
                            match sensor.sensor.aoa(&Measurement::Amplitudes(amps), &options) {
                                Ok(answer) => format!(
                                    "{},{led},{},{},{snr},ok",
                                    num(t0),
                                    deg(answer.aoa.alpha.x),
                                    deg(answer.aoa.alpha.y)
                                ),
                                Err(e) => format!("{},{led},,,{snr},{}", num(t0), e.status()),
                            }
                        }
                    }
                    Err(e) => format!("{},{led},,,,{}", num(t0), window_status(e)),
                };
                emit!(writeln!(output, "{row}"));
            }
            emit!(output.flush());
            summary.windows += 1;
            frames.clear();
        }
    }
    Ok(summary)
}

/// The status of a window that could not be demodulated.
fn window_status(e: &SignalError) -> &'static str {
    match e {
        SignalError::Saturated { .. } => "saturated",
        SignalError::RecordTooShortToDemodulate { .. } => "too_short",
        SignalError::TonesNotSeparable { .. } => "tone_collision",
        _ => "invalid_input",
    }
}

/// The positions of vx1, vx2, vy1, vy2 in a header.
fn header_columns(fields: &[&str]) -> Option<[usize; 4]> {
    let find = |name: &str| fields.iter().position(|f| f.eq_ignore_ascii_case(name));
    Some([find("vx1")?, find("vx2")?, find("vy1")?, find("vy2")?])
}

/// Four finite numbers at `columns`.
fn sample(fields: &[&str], columns: [usize; 4]) -> Option<[f64; 4]> {
    let mut frame = [0.0; 4];
    for (value, &c) in frame.iter_mut().zip(&columns) {
        *value = fields
            .get(c)?
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())?;
    }
    Some(frame)
}

/// A CSV field, quoted when it needs to be.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) || s.starts_with('#') {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
