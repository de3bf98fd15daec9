//! `track`: angles of arrival (one sensor) or positions (a rig) from a
//! live stream of raw samples (docs/model.md §8.5): rows of
//! `vx1,vx2,vy1,vy2` (volts) per sensor in, as they arrive (standard input,
//! or a recording file: psdcal-io's `SampleSource`); per window of `round(window fs)`
//! samples and per LED of tones.csv, one row out, flushed at the end of each
//! window (`daq-reader | psdcal track … | controller`):
//!
//! - one sensor (`--calibration`): `t_s,led,alpha_x_deg,alpha_y_deg,snr_db,status`;
//! - a rig (`--rig`, one stream of `4 S` channels, `track_rig.rs`):
//!   `t_s,led,sensors,x_world_mm,…,status`, the position and its covariance.
//!
//! Each window is demodulated on its own, exactly as `demodulate` treats a
//! record of the same samples (its own filter start, frequency estimate and
//! noise): the same samples give the same angles. `t_s` is the time of the
//! window's first sample, counted from the first sample of the stream.
//!
//! A line that is not a sample gives a row with the status `malformed_line`
//! (`line_too_long` for a line over 1 MiB, skipped without being held in
//! memory) and is not counted as a sample; the stream goes on. The samples
//! of a last, incomplete window are not answered; the summary says how many
//! ([`TrackSummary::warnings`]). Statuses per LED:
//! `ok`, `dark`, `saturated`, `too_short`, `tone_collision`, or the
//! location code of an angle or position that cannot be computed (e.g.
//! `outside_valid_region`, `too_few_sensors`).

use std::io::{BufRead, Write};
use std::path::PathBuf;

use psdcal_io::{IoError, Sample, SampleSource, StreamFault, Tones};
use psdcal_locate::{LocateOptions, Measurement, TrackFilter};
use psdcal_model::Amplitudes;
use psdcal_signal::tones::check_separable;
use psdcal_signal::{DemodConfig, RecordEstimate, SignalError, Window, Windows};

use crate::answer::loaded_sensor::LoadedSensor;
use crate::base::error::{Error, Result};
use crate::base::table::{deg, num};
use crate::signals::track_rig::{row_text, LedFilters, TrackRig};

/// Whose angles or positions `track` computes.
#[derive(Debug, Clone, PartialEq)]
pub enum TrackTarget {
    /// One sensor's calibration.json: angles of arrival.
    Sensor(PathBuf),
    /// A rig.json: positions in the world frame from every sensor's stream.
    Rig(PathBuf),
}

/// What `track` needs.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackRequest {
    /// The sensor or the rig.
    pub target: TrackTarget,
    /// Sample rate, Hz (a recording file may carry it instead).
    pub rate_hz: Option<f64>,
    /// tones.csv: the LEDs and their tones.
    pub tones: PathBuf,
    /// Window length, s.
    pub window_s: f64,
    /// The demodulation's parameters.
    pub config: DemodConfig,
    /// A recording file to read instead of the input stream.
    pub raw: Option<PathBuf>,
    /// A .tdms recording's channels (four per sensor); empty: the default.
    pub channels: Vec<String>,
    /// Bounds on the files read whole (docs/formats.md, "Limits").
    pub limits: psdcal_io::ReadLimits,
    /// The tracking filter of a rig's positions.
    pub filter: TrackFilter,
}

/// What `track` saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TrackSummary {
    /// Samples read.
    pub samples: u64,
    /// Windows answered.
    pub windows: u64,
    /// Malformed lines (too long ones included).
    pub malformed: u64,
    /// Samples of the last, incomplete window (not answered).
    pub unanswered: u64,
    /// The window's length, samples.
    pub window: u64,
}

impl TrackSummary {
    /// One line: samples, windows, malformed lines.
    pub fn text(&self) -> String {
        format!(
            "track: {} samples, {} windows, {} malformed lines",
            self.samples, self.windows, self.malformed
        )
    }

    /// What the stream left unanswered: the samples of a last window that
    /// the input ended before filling.
    pub fn warnings(&self) -> Vec<String> {
        if self.unanswered == 0 {
            return Vec::new();
        }
        vec![format!(
            "the input ended {} samples into a window of {}: those samples were not answered \
             (a window is answered once full)",
            self.unanswered, self.window
        )]
    }
}

const HEADER: &str = "t_s,led,alpha_x_deg,alpha_y_deg,snr_db,status";

/// The sensor or rig answering each window.
pub(crate) enum Answerer {
    Sensor(Box<LoadedSensor>),
    Rig(Box<TrackRig>),
}

/// Runs the stream from `input` (or the request's recording file) to
/// `output` until the input ends. See the module documentation.
///
/// Errors: the calibration, rig or tones file, an unusable rate, window or
/// tone set (checked before the first sample), reading the input or writing
/// the output.
pub fn track(
    request: &TrackRequest,
    input: impl BufRead,
    mut output: impl Write,
) -> Result<TrackSummary> {
    let Prepared {
        answerer,
        tones,
        mut source,
        fs,
        mut windows,
    } = prepare(request, input)?;
    let mut summary = TrackSummary {
        window: windows.window_len() as u64,
        ..TrackSummary::default()
    };
    // A reader that went away (`| head`) is an error too: the caller tells
    // it apart (`is_closed_output`) to end quietly with its own status.
    macro_rules! emit {
        ($result:expr) => {
            match $result {
                Ok(()) => {}
                Err(source) => {
                    return Err(Error::Io(psdcal_io::IoError::Write {
                        file: crate::base::stdout::STANDARD_OUTPUT.to_string(),
                        source,
                    }))
                }
            }
        };
    }
    let mut filters = LedFilters::new(&request.filter, tones.tones.len());
    let header = match &answerer {
        Answerer::Sensor(_) => HEADER.to_string(),
        Answerer::Rig(_) if filters.active() => format!(
            "{}{}",
            crate::signals::track_rig::HEADER,
            crate::signals::track_rig::VELOCITY_HEADER
        ),
        Answerer::Rig(_) => crate::signals::track_rig::HEADER.to_string(),
    };
    emit!(writeln!(output, "{header}").and_then(|()| output.flush()));
    let empty_fields = header.matches(',').count() - 1;
    let options = LocateOptions::default();
    while let Some(sample) = source.next_sample().map_err(stream_error)? {
        let values = match sample {
            Sample::Values(values) => values,
            other => {
                summary.malformed += 1;
                let t = (summary.samples as f64) / fs;
                let commas = ",".repeat(empty_fields);
                let status = unreadable_status(&other);
                emit!(writeln!(output, "{},{commas}{status}", num(t)).and_then(|()| output.flush()));
                continue;
            }
        };
        summary.samples += 1;
        if let Some(Window { t0_s, estimates }) = windows.push(&values) {
            let rows = match &answerer {
                Answerer::Sensor(sensor) => {
                    sensor_rows(sensor, &tones, &estimates[0], t0_s, &options)
                }
                Answerer::Rig(rig) => {
                    let mut fixes = rig.fixes(&tones, &estimates);
                    filters.apply(t0_s, &mut fixes);
                    let velocity = filters.active();
                    fixes.iter().map(|f| row_text(t0_s, f, velocity)).collect()
                }
            };
            for row in rows {
                emit!(writeln!(output, "{row}"));
            }
            emit!(output.flush());
            summary.windows += 1;
        }
    }
    summary.unanswered = windows.pending() as u64;
    Ok(summary)
}

/// The status of a line that is not a sample: `line_too_long` or
/// `malformed_line`.
fn unreadable_status(sample: &Sample) -> &'static str {
    match sample {
        Sample::TooLong => "line_too_long",
        _ => "malformed_line",
    }
}

/// What a stream needs, checked before the first sample.
pub(crate) struct Prepared<R> {
    pub answerer: Answerer,
    pub tones: Tones,
    pub source: SampleSource<R>,
    pub fs: f64,
    pub windows: Windows,
}

/// Reads the calibration or rig and the tones, opens the samples and checks
/// the rate, window, tones and filter.
pub(crate) fn prepare<R: BufRead>(request: &TrackRequest, input: R) -> Result<Prepared<R>> {
    let limits = request.limits;
    let answerer = match &request.target {
        TrackTarget::Sensor(path) => {
            Answerer::Sensor(Box::new(LoadedSensor::read_with(path, limits)?))
        }
        TrackTarget::Rig(path) => Answerer::Rig(Box::new(TrackRig::load(path, limits)?)),
    };
    let sensors: Vec<String> = match &answerer {
        Answerer::Sensor(_) => vec![String::new()],
        Answerer::Rig(rig) => rig.ids(),
    };
    let tones = Tones::read_with(&request.tones, limits)?;
    let (source, fs) = match &request.raw {
        Some(path) => SampleSource::file(path, &sensors, &request.channels, request.rate_hz)
            .map_err(stream_error)?,
        None => {
            let fs = request.rate_hz.ok_or_else(|| {
                Error::Options(
                    "no --rate: the samples on standard input need their rate as --rate HZ"
                        .to_string(),
                )
            })?;
            (SampleSource::lines(input, sensors.clone()), fs)
        }
    };
    if !(fs.is_finite() && fs > 0.0) {
        return Err(Error::Options(format!(
            "--rate {fs}: expected a finite, positive sample rate"
        )));
    }
    let window = (request.window_s * fs).round();
    if !(window >= 1.0 && window <= crate::signals::demodulate::MAX_RECORD_SAMPLES as f64) {
        return Err(Error::Options(format!(
            "--window {} s: expected between one sample and {} samples",
            request.window_s,
            crate::signals::demodulate::MAX_RECORD_SAMPLES
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
    if request.filter != TrackFilter::None && matches!(answerer, Answerer::Sensor(_)) {
        return Err(Error::Options(
            "--filter filters a rig's positions; expected --rig FILE with it".to_string(),
        ));
    }
    let windows = Windows::new(sensors.len(), window, fs, freqs, request.config);
    Ok(Prepared {
        answerer,
        tones,
        source,
        fs,
        windows,
    })
}

/// One sensor's rows of a window: angles per LED.
fn sensor_rows(
    sensor: &LoadedSensor,
    tones: &Tones,
    estimate: &std::result::Result<RecordEstimate<4>, SignalError>,
    t0: f64,
    options: &LocateOptions,
) -> Vec<String> {
    let mut rows = Vec::with_capacity(tones.tones.len());
    for (k, tone) in tones.tones.iter().enumerate() {
        let led = psdcal_io::csv_field(&tone.led);
        let row = match estimate {
            Ok(est) => {
                let t = &est.tones[k];
                let snr = num(t.min_snr_db());
                if t.dark {
                    format!("{},{led},,,{snr},dark", num(t0))
                } else {
                    match sensor.sensor.aoa(
                        &Measurement::Amplitudes(Amplitudes::from(t.amplitudes)),
                        options,
                    ) {
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
            Err(e) => format!("{},{led},,,,{}", num(t0), e.status()),
        };
        rows.push(row);
    }
    rows
}

/// A stream's refusal as the facade's error: the options' fault or the
/// header's in the words the stream gave.
pub(crate) fn stream_error(e: IoError) -> Error {
    match e {
        IoError::Stream {
            fault: StreamFault::Options,
            message,
        } => Error::Options(message),
        IoError::Stream {
            fault: StreamFault::Header,
            message,
        } => Error::Input(message),
        e => Error::Io(e),
    }
}
