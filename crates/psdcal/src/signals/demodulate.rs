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
use std::path::{Path, PathBuf};

use psdcal_io::{write_atomic, IoError, RawReader, Schedule, ScheduleRow, Tones};
use psdcal_signal::{
    demodulate_record, DemodConfig, RecordBuffer, RecordEstimate, SignalError, ToneEstimate,
};
use serde_json::json;

use crate::base::error::{Error, Result};
use crate::base::table::num;

/// The longest record demodulated, samples (64 MB of frames).
pub const MAX_RECORD_SAMPLES: usize = 2_000_000;

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
    check_request(request)?;
    let limits = request.limits;
    let schedule = Schedule::read_with(&request.schedule, limits)?;
    let tones = request.tones.as_ref().map(|t| Tones::read_with(t, limits));
    let tones = tones.transpose()?;
    let mut reader = RawReader::open_channels(&request.raw, request.rate_hz, &request.channels)?;
    let fs = reader.sample_rate_hz();
    let mut buffer = RecordBuffer::new();
    let mut records = Vec::new();
    let mut warnings = Vec::new();
    for row in &schedule.rows {
        let leds = tones_of(row, tones.as_ref(), request.frequency_hz)?;
        let (start, stop) = interval(row, &schedule, fs)?;
        let Some(record) = buffer.record(start, stop, |out, max| reader.read_frames(out, max))?
        else {
            return Err(past_the_end(row, &schedule, &reader, buffer.end()));
        };
        let freqs: Vec<f64> = leds.iter().map(|(_, f)| *f).collect();
        let outcome = demodulate_record(record, fs, &freqs, &request.config);
        let judged = RecordJudge {
            row,
            leds: &leds,
            place: place(row, &schedule),
        };
        records.extend(judged.outcomes(outcome, &mut warnings)?);
    }
    write_signals(&request.out, &reader, fs, &records)?;
    Ok(Demodulated {
        records,
        sample_rate_hz: fs,
        samples_read: reader.frames_read(),
        warnings,
    })
}

/// The request's own values, checked before any file is read.
fn check_request(request: &DemodulateRequest) -> Result<()> {
    if !(request.frequency_hz.is_finite() && request.frequency_hz > 0.0) {
        return Err(Error::Options(format!(
            "--frequency {} Hz: expected a finite, positive modulation frequency",
            request.frequency_hz
        )));
    }
    request
        .config
        .validate()
        .map_err(|e| Error::Options(e.to_string()))
}

/// `schedule.csv:LINE`.
fn place(row: &ScheduleRow, schedule: &Schedule) -> String {
    format!("{}:{}", schedule.source, row.line_no)
}

/// The row's interval as frames `[round(t_start fs), round(t_stop fs))`;
/// refused past [`MAX_RECORD_SAMPLES`].
fn interval(row: &ScheduleRow, schedule: &Schedule, fs: f64) -> Result<(u64, u64)> {
    let start = (row.t_start_s * fs).round();
    let stop = (row.t_stop_s * fs).round();
    let len = stop - start;
    if len > MAX_RECORD_SAMPLES as f64 {
        return Err(Error::Input(format!(
            "{}: the interval [{}, {}) s holds {} samples, more than the {} a record may \
             hold; expected shorter intervals",
            place(row, schedule),
            row.t_start_s,
            row.t_stop_s,
            len,
            MAX_RECORD_SAMPLES
        )));
    }
    Ok((start as u64, stop as u64))
}

/// The error of an interval that ends after the recording (`total` frames
/// read).
fn past_the_end(row: &ScheduleRow, schedule: &Schedule, reader: &RawReader, total: u64) -> Error {
    let fs = reader.sample_rate_hz();
    Error::Input(format!(
        "{}: the interval [{}, {}) s of image '{}' ends after the recording {} \
         ({} samples, {} s at {} Hz); expected intervals inside the recording",
        place(row, schedule),
        row.t_start_s,
        row.t_stop_s,
        row.image,
        reader.source(),
        total,
        num(total as f64 / fs),
        num(fs)
    ))
}

/// One schedule row's LEDs, judged from its record's demodulation.
struct RecordJudge<'a> {
    row: &'a ScheduleRow,
    leds: &'a [(String, f64)],
    place: String,
}

impl RecordJudge<'_> {
    /// `schedule.csv:LINE: record of image 'I', LED 'L'`.
    fn what(&self, led: &str) -> String {
        format!(
            "{}: record of image '{}', LED '{}'",
            self.place, self.row.image, led
        )
    }

    /// The row's LEDs joined by `;`.
    fn leds_text(&self) -> String {
        self.leds
            .iter()
            .map(|l| l.0.as_str())
            .collect::<Vec<_>>()
            .join(";")
    }

    fn outcome(
        &self,
        led: &str,
        status: RecordStatus,
        tone: Option<&ToneEstimate<4>>,
    ) -> RecordOutcome {
        RecordOutcome {
            image: self.row.image.clone(),
            led: led.to_string(),
            status,
            snr_db: tone.map(ToneEstimate::min_snr_db),
            amplitudes: tone.map(|t| t.amplitudes),
            line: self.row.line_no,
        }
    }

    /// Every LED's outcome, a warning per LED left out; an error that no
    /// status names (a rate or band the data cannot have) stops the run.
    fn outcomes(
        &self,
        outcome: std::result::Result<RecordEstimate<4>, SignalError>,
        warnings: &mut Vec<String>,
    ) -> Result<Vec<RecordOutcome>> {
        match outcome {
            Ok(estimate) => Ok(self
                .leds
                .iter()
                .zip(&estimate.tones)
                .map(|((led, _), tone)| {
                    let status = if tone.dark {
                        warnings.push(format!(
                            "{}: dark (the total light is at the noise); left out of signals.csv",
                            self.what(led)
                        ));
                        RecordStatus::Dark
                    } else {
                        RecordStatus::Ok
                    };
                    self.outcome(led, status, Some(tone))
                })
                .collect()),
            Err(e) => {
                let status = self.rejected_status(&e)?;
                warnings.push(format!(
                    "{}: {} ({e}); left out of signals.csv",
                    self.what(&self.leds_text()),
                    status.name()
                ));
                Ok(self
                    .leds
                    .iter()
                    .map(|(led, _)| self.outcome(led, status, None))
                    .collect())
            }
        }
    }

    /// The status of a record the data refused, or the error of one the
    /// set-up refused.
    fn rejected_status(&self, e: &SignalError) -> Result<RecordStatus> {
        match e {
            SignalError::RecordTooShortToDemodulate { .. } => Ok(RecordStatus::TooShort),
            SignalError::Saturated { .. } => Ok(RecordStatus::Saturated),
            SignalError::TonesNotSeparable { .. } => Ok(RecordStatus::ToneCollision),
            _ => {
                let advice = match e {
                    SignalError::BandAboveNyquist { .. } | SignalError::SampleRateTooLow { .. } => {
                        "; is the sample rate right? (--rate, or raw.csv's t_s: it must \
                         be well above twice the modulation frequency)"
                    }
                    _ => "",
                };
                Err(Error::Input(format!(
                    "{}: {e}{advice}",
                    self.what(&self.leds_text())
                )))
            }
        }
    }
}

/// signals.csv of the demodulated records (status `ok`), atomically.
fn write_signals(out: &Path, reader: &RawReader, fs: f64, records: &[RecordOutcome]) -> Result<()> {
    write_atomic(out, |w| {
        writeln!(
            w,
            "# demodulated by psdcal {} from {} ({} Hz); amplitudes in peak volts",
            env!("CARGO_PKG_VERSION"),
            reader.source().replace(['\n', '\r'], " "),
            num(fs)
        )?;
        writeln!(w, "image,led,vx1,vx2,vy1,vy2,snr_db")?;
        for r in records.iter().filter(|r| r.status == RecordStatus::Ok) {
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
    .map_err(|e: IoError| Error::Io(e))
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
