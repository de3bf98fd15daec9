//! Band-pass filtering of a stream that arrives in chunks: the state of the
//! recursion (two variables per second-order section and channel) is carried
//! from one chunk to the next, so filtering a record chunk by chunk gives the
//! same samples as filtering it whole, whatever the chunk sizes.
//!
//! # Equations
//!
//! Each section in direct form II transposed (docs/model.md §6,
//! [`crate::butterworth`]): `y[n] = b0 x[n] + z1`,
//! `z1 ← b1 x[n] − a1 y[n] + z2`, `z2 ← b2 x[n] − a2 y[n]`. The cascade is run
//! section by section over a chunk (each section is an independent recursion
//! on its input sequence, so the order of the loops does not change a single
//! operation).
//!
//! # Conventions
//!
//! Channels are numbered from 0; a frame is one sample of every channel
//! (`[vx1, vx2, vy1, vy2]` for a PSD). A new filter starts at rest (zero
//! state); [`StreamFilter::reset`] brings it back to rest.

use crate::butterworth::{BandPass, Biquad, MAX_ORDER};

/// A band-pass applied to `C` channels of a chunked stream.
#[derive(Debug, Clone)]
pub struct StreamFilter<const C: usize> {
    filter: BandPass,
    /// `z[channel][section] = [z1, z2]`.
    z: [[[f64; 2]; MAX_ORDER]; C],
}

impl<const C: usize> StreamFilter<C> {
    /// The filter `filter` on `C` channels, at rest.
    pub fn new(filter: BandPass) -> Self {
        Self {
            filter,
            z: [[[0.0; 2]; MAX_ORDER]; C],
        }
    }

    /// The band-pass.
    pub fn filter(&self) -> &BandPass {
        &self.filter
    }

    /// Back to rest (every channel).
    pub fn reset(&mut self) {
        self.z = [[[0.0; 2]; MAX_ORDER]; C];
    }

    /// Filters the next chunk of channel `channel` in place (a channel index
    /// at or above `C` leaves the data untouched). Orders 1–4 run every
    /// section on each sample in turn with the state in registers (the
    /// sections' recursions then overlap in the processor); the result is
    /// the same, operation for operation.
    pub fn process_channel(&mut self, channel: usize, chunk: &mut [f64]) {
        let Some(states) = self.z.get_mut(channel) else {
            return;
        };
        let sections = self.filter.sections();
        match sections.len() {
            1 => run_fixed::<1>(sections, states, chunk),
            2 => run_fixed::<2>(sections, states, chunk),
            3 => run_fixed::<3>(sections, states, chunk),
            4 => run_fixed::<4>(sections, states, chunk),
            _ => {
                for (section, z) in sections.iter().zip(states.iter_mut()) {
                    let [b0, b1, b2] = section.b;
                    let [_, a1, a2] = section.a;
                    let (mut z1, mut z2) = (z[0], z[1]);
                    for x in chunk.iter_mut() {
                        let y = b0 * *x + z1;
                        z1 = b1 * *x - a1 * y + z2;
                        z2 = b2 * *x - a2 * y;
                        *x = y;
                    }
                    *z = [z1, z2];
                }
            }
        }
    }

    /// Filters the next chunk of frames in place, every channel (the
    /// channels' recursions interleaved sample by sample). Orders 1–4 run
    /// every section on each frame in turn with the state in registers, as
    /// [`StreamFilter::process_channel`]; the same operations either way.
    pub fn process_frames(&mut self, frames: &mut [[f64; C]]) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (checked just above).
            return unsafe { self.process_frames_avx2(frames) };
        }
        self.process_frames_plain(frames)
    }

    /// [`StreamFilter::process_frames`] compiled for AVX2 (four channels in
    /// one register; no fused multiply-add, so the same operations and the
    /// same results).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn process_frames_avx2(&mut self, frames: &mut [[f64; C]]) {
        self.process_frames_plain(frames)
    }

    /// The body of [`StreamFilter::process_frames`].
    #[inline(always)]
    fn process_frames_plain(&mut self, frames: &mut [[f64; C]]) {
        match self.filter.sections().len() {
            1 => self.frames_fixed::<1>(frames),
            2 => self.frames_fixed::<2>(frames),
            3 => self.frames_fixed::<3>(frames),
            4 => self.frames_fixed::<4>(frames),
            _ => self.frames_by_section(frames),
        }
    }

    /// `N` sections on each frame in turn, the state in locals.
    #[inline(always)]
    fn frames_fixed<const N: usize>(&mut self, frames: &mut [[f64; C]]) {
        let sections = self.filter.sections();
        let mut coef = [[0.0; 5]; N];
        let mut z1 = [[0.0; C]; N];
        let mut z2 = [[0.0; C]; N];
        for s in 0..N {
            let q = &sections[s];
            coef[s] = [q.b[0], q.b[1], q.b[2], q.a[1], q.a[2]];
            for c in 0..C {
                [z1[s][c], z2[s][c]] = self.z[c][s];
            }
        }
        for frame in frames.iter_mut() {
            let mut v = *frame;
            for s in 0..N {
                let [b0, b1, b2, a1, a2] = coef[s];
                for c in 0..C {
                    let x = v[c];
                    let y = b0 * x + z1[s][c];
                    z1[s][c] = b1 * x - a1 * y + z2[s][c];
                    z2[s][c] = b2 * x - a2 * y;
                    v[c] = y;
                }
            }
            *frame = v;
        }
        for s in 0..N {
            for c in 0..C {
                self.z[c][s] = [z1[s][c], z2[s][c]];
            }
        }
    }

    /// Section by section over the chunk (any order).
    fn frames_by_section(&mut self, frames: &mut [[f64; C]]) {
        for (s, section) in self.filter.sections().iter().enumerate() {
            let [b0, b1, b2] = section.b;
            let [_, a1, a2] = section.a;
            let mut z1 = [0.0; C];
            let mut z2 = [0.0; C];
            for c in 0..C {
                z1[c] = self.z[c][s][0];
                z2[c] = self.z[c][s][1];
            }
            for frame in frames.iter_mut() {
                for c in 0..C {
                    let x = frame[c];
                    let y = b0 * x + z1[c];
                    z1[c] = b1 * x - a1 * y + z2[c];
                    z2[c] = b2 * x - a2 * y;
                    frame[c] = y;
                }
            }
            for c in 0..C {
                self.z[c][s] = [z1[c], z2[c]];
            }
        }
    }
}

/// `N` sections, sample by sample, the state in locals.
#[inline(always)]
fn run_fixed<const N: usize>(
    sections: &[Biquad],
    states: &mut [[f64; 2]; MAX_ORDER],
    chunk: &mut [f64],
) {
    let mut coef = [[0.0; 5]; N];
    let mut z = [[0.0; 2]; N];
    for s in 0..N {
        let q = &sections[s];
        coef[s] = [q.b[0], q.b[1], q.b[2], q.a[1], q.a[2]];
        z[s] = states[s];
    }
    for x in chunk.iter_mut() {
        let mut v = *x;
        for s in 0..N {
            let [b0, b1, b2, a1, a2] = coef[s];
            let y = b0 * v + z[s][0];
            z[s][0] = b1 * v - a1 * y + z[s][1];
            z[s][1] = b2 * v - a2 * y;
            v = y;
        }
        *x = v;
    }
    states[..N].copy_from_slice(&z);
}
