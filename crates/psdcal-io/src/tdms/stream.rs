//! The streaming half of the TDMS reader: each segment's raw-data layout
//! as the selected channels see it (contiguous or interleaved chunks, each
//! channel's offset and type) and the rows read from it, block by block.
//! The lead-ins, metadata and channel selection are in the parent module.

use std::io::SeekFrom;

use super::{read_error, ReadSeek, TdmsReader, BLOCK};
use crate::error::IoError;
use crate::limits::excerpt;
use crate::location::Location;
use crate::tdms_meta::{DataType, LeadIn, RawIndex, LEAD_IN, UNFINISHED};

/// A selected channel's place in the current segment.
#[derive(Debug, Clone, Copy)]
pub(super) struct Place {
    /// Byte offset within a chunk (contiguous) or within a row (interleaved).
    offset: u64,
    dtype: DataType,
    size: u64,
}

/// The current segment's raw data as the selected channels see it.
#[derive(Debug)]
pub(super) struct Layout {
    data_start: u64,
    chunk_bytes: u64,
    chunks: u64,
    /// Rows per chunk.
    rows: u64,
    interleaved: bool,
    big: bool,
    /// Interleaved: bytes per row.
    stride: u64,
    places: Vec<Place>,
    /// Next chunk and row within it.
    chunk: u64,
    row: u64,
}

impl TdmsReader {
    /// Moves to the next segment holding the selected channels; `false` at
    /// the end of the file.
    fn next_layout(&mut self) -> Result<bool, IoError> {
        while let Some((start, lead_in, meta)) = self.segment()? {
            if lead_in.daqmx() {
                return Err(self.error(format!(
                    "byte {start}: DAQmx raw data, which psdcal does not read; expected scaled \
                     values (or convert, e.g. with npTDMS, to .npy)"
                )));
            }
            if lead_in.has_meta() {
                if lead_in.new_list() {
                    self.list.clear();
                }
                for object in meta {
                    let id = self.by_path[&object.path];
                    let index = match object.index {
                        RawIndex::NoData => None,
                        RawIndex::New(ix) => Some(ix),
                        RawIndex::Same => Some(*self.last_index.get(&id).ok_or_else(|| {
                            self.error(format!(
                                "byte {start}: {} repeats a previous raw data index it never had; \
                                 expected a valid segment",
                                excerpt(&object.path)
                            ))
                        })?),
                    };
                    if let Some(ix) = index {
                        self.last_index.insert(id, ix);
                    }
                    match self.list.iter_mut().find(|(o, _)| *o == id) {
                        Some(entry) => entry.1 = index,
                        None => self.list.push((id, index)),
                    }
                }
            }
            let body = start + LEAD_IN;
            let data_start = body + lead_in.raw_offset;
            let end = match self.next_segment {
                Some(next) => next,
                None if lead_in.next_offset == UNFINISHED => self.file_len,
                None => body + lead_in.next_offset,
            };
            if !lead_in.has_raw() || end == data_start {
                continue;
            }
            if let Some(layout) = self.layout_of(start, &lead_in, data_start, end)? {
                self.layout = Some(layout);
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// The selected channels' places in a segment's raw data (`None`: they
    /// have no data there).
    fn layout_of(
        &self,
        start: u64,
        lead_in: &LeadIn,
        data_start: u64,
        end: u64,
    ) -> Result<Option<Layout>, IoError> {
        let interleaved = lead_in.interleaved();
        let mut offset = 0u64;
        let mut rows: Option<u64> = None;
        let mut places: Vec<Option<Place>> = vec![None; self.selected.len()];
        let overflow = || self.error(format!("byte {start}: the chunk size overflows"));
        for &(object, index) in &self.list {
            let Some(ix) = index else { continue };
            let size = if interleaved {
                let size = ix.dtype.size().filter(|&s| s > 0).ok_or_else(|| {
                    self.error(format!(
                        "byte {start}: interleaved {} values; expected fixed-size values",
                        ix.dtype.name()
                    ))
                })?;
                if *rows.get_or_insert(ix.count) != ix.count {
                    return Err(self.error(format!(
                        "byte {start}: interleaved channels with different value counts; \
                         expected one count"
                    )));
                }
                size
            } else {
                ix.bytes
            };
            if let Some(k) = self.selected.iter().position(|s| s.object == object) {
                if !ix.dtype.is_sample() {
                    return Err(self.error(format!(
                        "byte {start}: channel {} holds {} values; expected numbers (integers or \
                         floats)",
                        self.selected[k].name,
                        ix.dtype.name()
                    )));
                }
                places[k] = Some(Place {
                    offset,
                    dtype: ix.dtype,
                    size: ix.dtype.size().unwrap_or(0),
                });
                if !interleaved {
                    match rows {
                        None => rows = Some(ix.count),
                        Some(r) if r != ix.count => {
                            return Err(self.error(format!(
                                "byte {start}: the selected channels have different numbers of \
                                 values per chunk ({r} and {}); expected one sample clock",
                                ix.count
                            )))
                        }
                        Some(_) => {}
                    }
                }
            }
            offset = offset.checked_add(size).ok_or_else(overflow)?;
        }
        let (stride, chunk_bytes) = if interleaved {
            let r = rows.unwrap_or(0);
            (offset, offset.checked_mul(r).ok_or_else(overflow)?)
        } else {
            (0, offset)
        };
        let present = places.iter().filter(|p| p.is_some()).count();
        if present == 0 {
            return Ok(None);
        }
        if present < places.len() {
            let missing = places.iter().position(Option::is_none).unwrap_or(0);
            return Err(self.error(format!(
                "byte {start}: channel {} has no values in a segment where the other selected \
                 channels have some; expected channels of one sample clock",
                self.selected[missing].name
            )));
        }
        let len = end - data_start;
        if chunk_bytes == 0 {
            return Ok(None);
        }
        let chunks = len / chunk_bytes;
        if !len.is_multiple_of(chunk_bytes) && lead_in.next_offset != UNFINISHED {
            return Err(self.error(format!(
                "byte {data_start}: {len} bytes of raw data are not a whole number of chunks of \
                 {chunk_bytes} bytes; expected a valid segment"
            )));
        }
        Ok(Some(Layout {
            data_start,
            chunk_bytes,
            chunks,
            rows: rows.unwrap_or(0),
            interleaved,
            big: lead_in.big_endian(),
            stride,
            places: places.into_iter().flatten().collect(),
            chunk: 0,
            row: 0,
        }))
    }

    /// Appends up to `max` rows (one value per selected channel each) to
    /// `out`; returns how many (0 at the end of the file).
    pub fn read_rows(&mut self, out: &mut Vec<f64>, max: usize) -> Result<usize, IoError> {
        let k = self.selected.len();
        let mut done = 0usize;
        while done < max {
            let need_layout = match &self.layout {
                Some(l) => l.chunk >= l.chunks || l.rows == 0,
                None => true,
            };
            if need_layout {
                self.layout = None;
                if !self.next_layout()? {
                    break;
                }
                continue;
            }
            let Some(layout) = self.layout.as_mut() else {
                break;
            };
            let m = (max - done)
                .min((layout.rows - layout.row) as usize)
                .min(BLOCK as usize);
            let base = out.len();
            out.resize(base + m * k, 0.0);
            let chunk_start = layout.data_start + layout.chunk * layout.chunk_bytes;
            let big = layout.big;
            if layout.interleaved {
                let at = chunk_start + layout.row * layout.stride;
                let bytes = m * layout.stride as usize;
                self.scratch.resize(bytes, 0);
                read_at(&mut self.input, at, &mut self.scratch)
                    .map_err(|e| read_error(&self.source, e))?;
                for (c, place) in layout.places.iter().enumerate() {
                    let (o, s) = (place.offset as usize, place.size as usize);
                    for r in 0..m {
                        let b = &self.scratch[r * layout.stride as usize + o..][..s];
                        out[base + r * k + c] = place.dtype.decode(b, big);
                    }
                }
            } else {
                for (c, place) in layout.places.iter().enumerate() {
                    let at = chunk_start + place.offset + layout.row * place.size;
                    let s = place.size as usize;
                    self.scratch.resize(m * s, 0);
                    read_at(&mut self.input, at, &mut self.scratch)
                        .map_err(|e| read_error(&self.source, e))?;
                    for (r, b) in self.scratch.chunks_exact(s).enumerate() {
                        out[base + r * k + c] = place.dtype.decode(b, big);
                    }
                }
            }
            layout.row += m as u64;
            if layout.row == layout.rows {
                layout.row = 0;
                layout.chunk += 1;
            }
            for (c, sel) in self.selected.iter().enumerate() {
                for r in 0..m {
                    let v = &mut out[base + r * k + c];
                    if let Some(s) = &sel.scaling {
                        *v = s.apply(*v);
                    }
                    if !v.is_finite() {
                        return Err(IoError::Structure {
                            at: Location::file(&self.source),
                            message: format!(
                                "sample row {} (0-based), channel {}: not a finite number; \
                                 expected finite volts",
                                self.rows_read + r as u64,
                                sel.name
                            ),
                        });
                    }
                }
            }
            self.rows_read += m as u64;
            done += m;
        }
        Ok(done)
    }
}

fn read_at(input: &mut Box<dyn ReadSeek>, at: u64, buf: &mut [u8]) -> std::io::Result<()> {
    input.seek(SeekFrom::Start(at))?;
    input.read_exact(buf)
}
