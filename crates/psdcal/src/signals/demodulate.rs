//! `demodulate`: a raw recording and its schedule in, signals.csv out
//! (docs/formats.md "Raw recordings", docs/model.md §8 "Demodulation").
//!
//! The recording is read frame by frame (psdcal-io's [`RawReader`]); the
//! schedule's intervals, in time order, are cut out of the stream and each
//! demodulated on its own (psdcal-signal's [`demodulate_record`]): its own
//! filter start, frequency estimate and noise. Memory holds one record at a
//! time (at most [`MAX_RECORD_SAMPLES`] samples), whatever the file size.
//!
//! Conventions:
//! - an interval `[t_start, t_stop)` is the samples `round(t_start fs) …
//!   round(t_stop fs) − 1` (the nearest samples: `t fs` is rarely an integer);
//! - with an `led` column (time multiplexing) the LED's tone is its
//!   `frequency_hz` in tones.csv when given there, else `--frequency`;
//!   without it (frequency multiplexing) every LED of tones.csv is on in
//!   every interval and gets its own row;
//! - amplitudes are peak volts; `snr_db` is the record's lowest channel SNR;
//! - a record that is too short, saturated, dark (its total light at the
//!   noise) or whose tones the window cannot separate gets that status, a
//!   warning naming it, and no row in signals.csv.
//!
//! An interval past the recording's end is an error naming the schedule's
//! line.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

use psdcal_io::{write_atomic, Frame, IoError, RawReader, Schedule, ScheduleRow, Tones};
use psdcal_signal::{demodulate_record, DemodConfig, SignalError};
use serde_json::json;

use crate::base::error::{Error, Result};
use crate::base::table::num;

/// The longest record demodulated, samples (64 MB of frames).
pub const MAX_RECORD_SAMPLES: usize = 2_000_000;

/// Frames read from the recording at a time.
const CHUNK: usize = 65_536;

/// What `demodulate` reads and writes.
#[derive(Debug, Clone, PartialEq)]
pub struct DemodulateRequest {
    /// raw.csv, raw.npy or raw.tdms.
    pub raw: PathBuf,
    /// `--rate`, Hz (raw.npy needs it; raw.csv may carry `t_s` instead).
    pub rate_hz: Option<f64>,
    /// schedule.csv.
    pub schedule: PathBuf,
    /// tones.csv (frequency multiplexing, or per-LED tones).
    pub tones: Option<PathBuf>,
    /// The modulation frequency of time-multiplexed LEDs without a tone, Hz.
    pub frequency_hz: f64,
    /// signals.csv to write.
    pub out: PathBuf,
    /// The demodulation's parameters.
    pub config: DemodConfig,
    /// A .tdms recording's four channels (vx1, vx2, vy1, vy2 in order:
    /// `group/channel`, a unique channel name or a TDMS path); empty: the
    /// default (docs/formats.md).
    pub channels: Vec<String>,
    /// Bounds on the files read whole (docs/formats.md, "Limits").
    pub limits: psdcal_io::ReadLimits,
}

/// The fate of one (image, LED) of the schedule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum RecordStatus {
    /// Demodulated and written.
    Ok,
    /// Too short for the filter's transient and a window.
    TooShort,
    /// A sample at the ADC's range.
    Saturated,
    /// The total light is at the noise.
    Dark,
    /// Tones closer than the record's window separates.
    ToneCollision,
}

impl RecordStatus {
    /// The status as written in summaries.
    pub fn name(self) -> &'static str {
        match self {
            RecordStatus::Ok => "ok",
            RecordStatus::TooShort => "too_short",
            RecordStatus::Saturated => "saturated",
            RecordStatus::Dark => "dark",
            RecordStatus::ToneCollision => "tone_collision",
        }
    }
}

/// One (image, LED) of the schedule.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordOutcome {
    /// Image identifier.
    pub image: String,
    /// LED identifier.
    pub led: String,
    /// Its status.
    pub status: RecordStatus,
    /// Lowest channel SNR, dB (demodulated records).
    pub snr_db: Option<f64>,
    /// Amplitudes `vx1, vx2, vy1, vy2`, peak volts (demodulated records).
    pub amplitudes: Option<[f64; 4]>,
    /// The schedule line.
    pub line: usize,
}

/// What `demodulate` did.
#[derive(Debug, Clone, PartialEq)]
pub struct Demodulated {
    /// Every (image, LED), in schedule order.
    pub records: Vec<RecordOutcome>,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Samples read from the recording.
    pub samples_read: u64,
    /// One warning per record left out.
    pub warnings: Vec<String>,
}

/// The tones of one interval: (LED, frequency).
fn tones_of(
    row: &ScheduleRow,
    tones: Option<&Tones>,
    frequency_hz: f64,
) -> Result<Vec<(String, f64)>> {
    match (&row.led, tones) {
        (Some(led), tones) => {
            let f = tones
                .and_then(|t| t.tones.iter().find(|t| &t.led == led))
                .map_or(frequency_hz, |t| t.frequency_hz);
            Ok(vec![(led.clone(), f)])
        }
        (None, Some(tones)) => Ok(tones
            .tones
            .iter()
            .map(|t| (t.led.clone(), t.frequency_hz))
            .collect()),
        (None, None) => Err(Error::Options(
            "the schedule has no led column (frequency multiplexing): give the LEDs' tones \
             with --tones tones.csv, or add an led column"
                .to_string(),
        )),
    }
}

/// Demodulates every interval of the schedule and writes signals.csv (with
/// `snr_db`). See the module documentation.
pub fn demodulate(request: &DemodulateRequest) -> Result<Demodulated> {
    if !(request.frequency_hz.is_finite() && request.frequency_hz > 0.0) {
        return Err(Error::Options(format!(
            "--frequency {} Hz: expected a finite, positive modulation frequency",
            request.frequency_hz
        )));
    }
    request
        .config
        .validate()
        .map_err(|e| Error::Options(e.to_string()))?;
    let limits = request.limits;
    let schedule = Schedule::read_with(&request.schedule, limits)?;
    let tones = request.tones.as_ref().map(|t| Tones::read_with(t, limits));
    let tones = tones.transpose()?;
    let mut reader = RawReader::open_channels(&request.raw, request.rate_hz, &request.channels)?;
    let fs = reader.sample_rate_hz();
    let mut buffer: Vec<Frame> = Vec::new();
    // Absolute index of buffer[0].
    let mut buffer_start: u64 = 0;
    let mut ended = false;
    let mut records = Vec::new();
    let mut warnings = Vec::new();
    let place = |row: &ScheduleRow| format!("{}:{}", schedule.source, row.line_no);
    for row in &schedule.rows {
        let leds = tones_of(row, tones.as_ref(), request.frequency_hz)?;
        let start = (row.t_start_s * fs).round();
        let stop = (row.t_stop_s * fs).round();
        let len = stop - start;
        if len > MAX_RECORD_SAMPLES as f64 {
            return Err(Error::Input(format!(
                "{}: the interval [{}, {}) s holds {} samples, more than the {} a record may \
                 hold; expected shorter intervals",
                place(row),
                row.t_start_s,
                row.t_stop_s,
                len,
                MAX_RECORD_SAMPLES
            )));
        }
        let (start, stop) = (start as u64, stop as u64);
        // Drop what lies before the record, then read up to its end.
        let drop = (start.saturating_sub(buffer_start) as usize).min(buffer.len());
        buffer.drain(..drop);
        buffer_start += drop as u64;
        while buffer_start + (buffer.len() as u64) < stop && !ended {
            let want = (stop - buffer_start - buffer.len() as u64).min(CHUNK as u64) as usize;
            if reader.read_frames(&mut buffer, want.max(1))? == 0 {
                ended = true;
            }
            // Frames before the record are not kept.
            if buffer_start < start {
                let drop = ((start - buffer_start) as usize).min(buffer.len());
                buffer.drain(..drop);
                buffer_start += drop as u64;
            }
        }
        if buffer_start + (buffer.len() as u64) < stop || buffer_start > start {
            let total = buffer_start + buffer.len() as u64;
            return Err(Error::Input(format!(
                "{}: the interval [{}, {}) s of image '{}' ends after the recording {} \
                 ({} samples, {} s at {} Hz); expected intervals inside the recording",
                place(row),
                row.t_start_s,
                row.t_stop_s,
                row.image,
                reader.source(),
                total,
                num(total as f64 / fs),
                num(fs)
            )));
        }
        let record = &buffer[(start - buffer_start) as usize..(stop - buffer_start) as usize];
        let freqs: Vec<f64> = leds.iter().map(|(_, f)| *f).collect();
        let outcome = demodulate_record(record, fs, &freqs, &request.config);
        let what = |led: &str| {
            format!(
                "{}: record of image '{}', LED '{}'",
                place(row),
                row.image,
                led
            )
        };
        let rejected = |status: RecordStatus| -> Vec<RecordOutcome> {
            leds.iter()
                .map(|(led, _)| RecordOutcome {
                    image: row.image.clone(),
                    led: led.clone(),
                    status,
                    snr_db: None,
                    amplitudes: None,
                    line: row.line_no,
                })
                .collect()
        };
        match outcome {
            Ok(estimate) => {
                for ((led, _), tone) in leds.iter().zip(&estimate.tones) {
                    let status = if tone.dark {
                        warnings.push(format!(
                            "{}: dark (the total light is at the noise); left out of signals.csv",
                            what(led)
                        ));
                        RecordStatus::Dark
                    } else {
                        RecordStatus::Ok
                    };
                    records.push(RecordOutcome {
                        image: row.image.clone(),
                        led: led.clone(),
                        status,
                        snr_db: Some(tone.min_snr_db()),
                        amplitudes: Some(tone.amplitudes),
                        line: row.line_no,
                    });
                }
            }
            Err(e) => {
                let status = match &e {
                    SignalError::RecordTooShortToDemodulate { .. } => RecordStatus::TooShort,
                    SignalError::Saturated { .. } => RecordStatus::Saturated,
                    SignalError::TonesNotSeparable { .. } => RecordStatus::ToneCollision,
                    _ => {
                        let advice = match &e {
                            SignalError::BandAboveNyquist { .. }
                            | SignalError::SampleRateTooLow { .. } => {
                                "; is the sample rate right? (--rate, or raw.csv's t_s: it must \
                                 be well above twice the modulation frequency)"
                            }
                            _ => "",
                        };
                        return Err(Error::Input(format!(
                            "{}: {e}{advice}",
                            what(
                                &leds
                                    .iter()
                                    .map(|l| l.0.as_str())
                                    .collect::<Vec<_>>()
                                    .join(";")
                            )
                        )));
                    }
                };
                let leds_text: Vec<&str> = leds.iter().map(|l| l.0.as_str()).collect();
                warnings.push(format!(
                    "{}: {} ({e}); left out of signals.csv",
                    what(&leds_text.join(";")),
                    status.name()
                ));
                records.extend(rejected(status));
            }
        }
    }
    let written: Vec<&RecordOutcome> = records
        .iter()
        .filter(|r| r.status == RecordStatus::Ok)
        .collect();
    write_atomic(&request.out, |w| {
        writeln!(
            w,
            "# demodulated by psdcal {} from {} ({} Hz); amplitudes in peak volts",
            env!("CARGO_PKG_VERSION"),
            reader.source().replace(['\n', '\r'], " "),
            num(fs)
        )?;
        writeln!(w, "image,led,vx1,vx2,vy1,vy2,snr_db")?;
        for r in &written {
            let a = r.amplitudes.unwrap_or_default();
            writeln!(
                w,
                "{},{},{},{},{},{},{}",
                psdcal_io::csv_field(&r.image),
                psdcal_io::csv_field(&r.led),
                num(a[0]),
                num(a[1]),
                num(a[2]),
                num(a[3]),
                num(r.snr_db.unwrap_or_default())
            )?;
        }
        Ok(())
    })
    .map_err(|e: IoError| Error::Io(e))?;
    Ok(Demodulated {
        records,
        sample_rate_hz: fs,
        samples_read: reader.frames_read(),
        warnings,
    })
}

impl Demodulated {
    /// Records per status.
    pub fn counts(&self) -> BTreeMap<&'static str, usize> {
        let mut counts = BTreeMap::new();
        for r in &self.records {
            *counts.entry(r.status.name()).or_insert(0) += 1;
        }
        counts
    }

    /// `(min, median, max)` of the written records' SNR, dB.
    pub fn snr_range(&self) -> Option<(f64, f64, f64)> {
        let mut snr: Vec<f64> = self
            .records
            .iter()
            .filter(|r| r.status == RecordStatus::Ok)
            .filter_map(|r| r.snr_db)
            .collect();
        snr.sort_by(f64::total_cmp);
        let (first, last) = (snr.first()?, snr.last()?);
        Some((*first, snr[snr.len() / 2], *last))
    }

    /// Records written to signals.csv.
    pub fn written(&self) -> usize {
        self.records
            .iter()
            .filter(|r| r.status == RecordStatus::Ok)
            .count()
    }

    /// The `--json` summary.
    pub fn to_json(&self) -> serde_json::Value {
        let snr = self
            .snr_range()
            .map(|(lo, med, hi)| json!({"min": lo, "median": med, "max": hi}));
        let rejected: Vec<_> = self
            .records
            .iter()
            .filter(|r| r.status != RecordStatus::Ok)
            .map(|r| json!({"image": r.image, "led": r.led, "status": r.status.name(), "line": r.line}))
            .collect();
        json!({
            "records": self.records.len(),
            "written": self.written(),
            "sample_rate_hz": self.sample_rate_hz,
            "samples_read": self.samples_read,
            "status": self.counts(),
            "snr_db": snr,
            "rejected": rejected,
        })
    }

    /// The text summary (several lines).
    pub fn summary(&self, out: &std::path::Path) -> String {
        let counts: Vec<String> = self
            .counts()
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect();
        let mut text = format!(
            "demodulated {} records ({}) from {} samples at {} Hz; wrote {} rows to {}",
            self.records.len(),
            counts.join(", "),
            self.samples_read,
            num(self.sample_rate_hz),
            self.written(),
            out.display()
        );
        if let Some((lo, med, hi)) = self.snr_range() {
            text += &format!(
                "\nSNR (lowest channel): min {lo:.1} dB, median {med:.1} dB, max {hi:.1} dB"
            );
        }
        text
    }
}
