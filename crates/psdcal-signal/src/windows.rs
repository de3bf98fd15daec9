//! A live stream of samples cut into windows (docs/model.md §8.5): the
//! frames of `S` sensors (four channels each) arrive one at a time; every
//! `len` frames the window is complete, and each sensor's window is
//! demodulated on its own exactly as a record of the same samples
//! ([`demodulate_record`]: its own filter start, frequency estimate and
//! noise), then the window starts again empty.
//!
//! Conventions: the window's time `t0 = (n − len) / fs` is that of its first
//! sample, `n` the frames pushed so far (counted from the stream's first
//! frame); a trailing partial window is not demodulated ([`Windows::pending`]
//! says how many frames it holds).

use crate::error::SignalError;
use crate::record::{demodulate_record, DemodConfig, RecordEstimate};

/// One complete window, demodulated.
#[derive(Debug, Clone, PartialEq)]
pub struct Window {
    /// Time of the window's first sample, s from the stream's first sample.
    pub t0_s: f64,
    /// Each sensor's estimate (or why its window could not be
    /// demodulated), in the order of the frames' sensors.
    pub estimates: Vec<Result<RecordEstimate<4>, SignalError>>,
}

/// The windowing of a stream of `S` sensors' frames (module documentation).
#[derive(Debug, Clone)]
pub struct Windows {
    len: usize,
    sample_rate_hz: f64,
    tones_hz: Vec<f64>,
    config: DemodConfig,
    /// The current window's frames, one list per sensor.
    frames: Vec<Vec<[f64; 4]>>,
    /// Frames pushed so far.
    samples: u64,
}

impl Windows {
    /// Windows of `len` frames of `sensors` sensors sampled at
    /// `sample_rate_hz`, demodulated at `tones_hz` with `config`.
    pub fn new(
        sensors: usize,
        len: usize,
        sample_rate_hz: f64,
        tones_hz: Vec<f64>,
        config: DemodConfig,
    ) -> Self {
        Self {
            len,
            sample_rate_hz,
            tones_hz,
            config,
            frames: vec![Vec::with_capacity(len); sensors],
            samples: 0,
        }
    }

    /// Adds one frame (`4 S` values: each sensor's `vx1, vx2, vy1, vy2` in
    /// turn); returns the window it completes, demodulated.
    pub fn push(&mut self, values: &[f64]) -> Option<Window> {
        for (s, f) in self.frames.iter_mut().enumerate() {
            f.push([
                values[4 * s],
                values[4 * s + 1],
                values[4 * s + 2],
                values[4 * s + 3],
            ]);
        }
        self.samples += 1;
        if self.frames[0].len() < self.len {
            return None;
        }
        let t0_s = (self.samples - self.len as u64) as f64 / self.sample_rate_hz;
        let estimates = self
            .frames
            .iter()
            .map(|f| demodulate_record(f, self.sample_rate_hz, &self.tones_hz, &self.config))
            .collect();
        self.frames.iter_mut().for_each(Vec::clear);
        Some(Window { t0_s, estimates })
    }

    /// A window's length, frames.
    pub fn window_len(&self) -> usize {
        self.len
    }

    /// Frames pushed so far.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Frames of the current, incomplete window.
    pub fn pending(&self) -> usize {
        self.frames.first().map_or(0, Vec::len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A window's estimate equals the record of the same samples
    /// demodulated alone, and its time is that of its first sample.
    #[test]
    fn a_window_is_the_record_of_its_samples() {
        let fs = 20_000.0;
        let tone = 1_000.0;
        let frame = |n: usize| {
            let phase = std::f64::consts::TAU * tone * n as f64 / fs;
            [
                0.5 * phase.sin(),
                0.4 * phase.sin(),
                0.3 * phase.sin(),
                0.2 * phase.sin(),
            ]
        };
        let len = 1_000;
        let config = DemodConfig::default();
        let mut windows = Windows::new(1, len, fs, vec![tone], config);
        let mut done = Vec::new();
        for n in 0..2 * len + 7 {
            done.extend(windows.push(&frame(n)));
        }
        assert_eq!(done.len(), 2);
        assert_eq!(windows.pending(), 7);
        assert_eq!(windows.samples(), 2 * len as u64 + 7);
        let second: Vec<[f64; 4]> = (len..2 * len).map(frame).collect();
        let alone = demodulate_record(&second, fs, &[tone], &config);
        assert_eq!(done[1].estimates[0], alone);
        assert_eq!(done[1].t0_s, len as f64 / fs);
        let a = done[1].estimates[0].as_ref().unwrap().tones[0].amplitudes;
        assert!((a[0] - 0.5).abs() < 1e-6, "{a:?}");
    }
}
