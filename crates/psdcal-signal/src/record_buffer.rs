//! The records of a schedule cut out of a recording read in order
//! (docs/formats.md "Raw recordings"): frames are read in chunks of at most
//! [`CHUNK`] and kept only from the current record's first frame on, so
//! memory holds one record (plus a chunk) whatever the recording's length.
//!
//! Conventions: a record is the frames `[start, stop)` counted from the
//! recording's first frame; records are asked for in time order (a record
//! may overlap the previous one, never start before the previous start).

/// Frames read from the recording at a time.
pub const CHUNK: usize = 65_536;

/// The frames kept from a recording read in order.
#[derive(Debug, Clone, Default)]
pub struct RecordBuffer {
    /// The kept frames, from frame `first` of the recording on.
    frames: Vec<[f64; 4]>,
    /// Index of `frames[0]` in the recording.
    first: u64,
    /// The reader said the recording ended.
    ended: bool,
}

impl RecordBuffer {
    /// An empty buffer at the recording's start.
    pub fn new() -> Self {
        Self::default()
    }

    /// The frames `[start, stop)`, reading on with `read(out, max)` (which
    /// appends at most `max` frames to `out` and returns how many, 0 at the
    /// recording's end). `None` when the recording ends before `stop`, or
    /// when `start` lies before frames already dropped.
    pub fn record<E>(
        &mut self,
        start: u64,
        stop: u64,
        mut read: impl FnMut(&mut Vec<[f64; 4]>, usize) -> Result<usize, E>,
    ) -> Result<Option<&[[f64; 4]]>, E> {
        // Drop what lies before the record, then read up to its end.
        self.drop_before(start);
        while self.end() < stop && !self.ended {
            let want = (stop - self.end()).min(CHUNK as u64) as usize;
            if read(&mut self.frames, want.max(1))? == 0 {
                self.ended = true;
            }
            // Frames before the record are not kept.
            self.drop_before(start);
        }
        if self.end() < stop || self.first > start {
            return Ok(None);
        }
        let from = (start - self.first) as usize;
        let to = (stop - self.first) as usize;
        Ok(Some(&self.frames[from..to]))
    }

    /// One past the last frame read and kept, counted from the recording's
    /// first frame.
    pub fn end(&self) -> u64 {
        self.first + self.frames.len() as u64
    }

    fn drop_before(&mut self, start: u64) {
        if self.first < start {
            let drop = ((start - self.first) as usize).min(self.frames.len());
            self.frames.drain(..drop);
            self.first += drop as u64;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A recording of `total` frames whose frame `n` is `[n, n, n, n]`,
    /// read `step` frames at most per call.
    fn reader(
        total: u64,
        step: usize,
    ) -> impl FnMut(&mut Vec<[f64; 4]>, usize) -> Result<usize, ()> {
        let mut next = 0u64;
        move |out, max| {
            let n = (max.min(step) as u64).min(total - next);
            out.extend((next..next + n).map(|i| [i as f64; 4]));
            next += n;
            Ok(n as usize)
        }
    }

    #[test]
    fn records_are_the_frames_of_their_interval() {
        let mut read = reader(1_000, 97);
        let mut buffer = RecordBuffer::new();
        for (start, stop) in [(10, 20), (15, 400), (400, 1_000), (999, 1_000)] {
            let record = buffer.record(start, stop, &mut read).unwrap().unwrap();
            let expected: Vec<[f64; 4]> = (start..stop).map(|i| [i as f64; 4]).collect();
            assert_eq!(record, expected.as_slice());
        }
        assert!(buffer.record(990, 1_001, &mut read).unwrap().is_none());
    }

    #[test]
    fn a_record_before_dropped_frames_is_refused() {
        let mut read = reader(100, 1_000);
        let mut buffer = RecordBuffer::new();
        assert!(buffer.record(50, 60, &mut read).unwrap().is_some());
        assert!(buffer.record(40, 55, &mut read).unwrap().is_none());
    }
}
