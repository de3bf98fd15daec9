//! NI TDMS recordings read as a stream of rows of selected channels
//! (docs/formats.md, "Raw recordings", raw.tdms), in bounded memory
//! whatever the file size. The segment structure is in `tdms_meta.rs`.
//!
//! Two passes over the file: the first reads only the segments' lead-ins
//! and metadata (the channels, their properties: `wf_increment`, NI's
//! scaling), the second streams the raw data. Segments may be appended
//! without metadata (the previous segment's objects), with incremental
//! metadata (objects added or re-indexed; an index `0` repeats the
//! object's previous one) or with a new object list. Within a segment the
//! raw data is a sequence of equal chunks; per chunk, the channels' values
//! are contiguous (channel after channel) or interleaved (one value of each
//! channel in turn). Contiguous chunks are read channel by channel in blocks
//! (seeking), so memory stays at a few blocks of rows.
//!
//! Samples: integers (i8–i64, u8–u64) and floats (f32, f64), either byte
//! order, each converted to f64, then scaled when the channel (or its group,
//! or the file) carries NI scaling properties with `NI_Scaling_Status`
//! other than `scaled`: `NI_Number_Of_Scales` scales, each `Linear`
//! (`y = slope x + intercept`) or `Polynomial` (`y = Σ cᵢ xⁱ`), fed by the
//! raw values or by another scale (`…_Input_Source`); the last scale gives
//! the value. Other scale types and DAQmx raw data are errors.
//!
//! Every selected channel must have values in the same segments, as many
//! per chunk as the others (one sample clock). Every sample must be finite.
//! Errors name the file and the byte offset (or the 0-based sample row).

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use crate::error::{IoError, Location};
use crate::limits::excerpt;
use crate::tdms_meta::{
    channel_names, group_path, parse_metadata, DataType, Index, LeadIn, MetaObject, RawIndex,
    Value, LEAD_IN, UNFINISHED,
};
use crate::tdms_scaling::Scaling;

/// The largest metadata block of one segment, bytes.
const MAX_METADATA: u64 = 16 << 20;
/// The most objects (root, groups, channels) a file may name.
const MAX_OBJECTS: usize = 100_000;
/// The most property bytes kept over the whole file.
const MAX_PROPERTY_BYTES: usize = 16 << 20;
/// Rows read per channel and block of a contiguous chunk.
const BLOCK: u64 = 8192;
/// The names of the default channels, in frame order.
pub const TDMS_DEFAULT_CHANNELS: [&str; 4] = ["vx1", "vx2", "vy1", "vy2"];

/// A seekable byte source.
trait ReadSeek: Read + Seek {}
impl<T: Read + Seek> ReadSeek for T {}

/// One object of the file: its path and properties.
#[derive(Debug)]
struct Object {
    path: String,
    properties: HashMap<String, Value>,
}

/// A selected channel.
#[derive(Debug)]
struct Selected {
    object: usize,
    name: String,
    scaling: Option<Scaling>,
}

/// A selected channel's place in the current segment.
#[derive(Debug, Clone, Copy)]
struct Place {
    /// Byte offset within a chunk (contiguous) or within a row (interleaved).
    offset: u64,
    dtype: DataType,
    size: u64,
}

/// The current segment's raw data as the selected channels see it.
#[derive(Debug)]
struct Layout {
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

/// A TDMS file read row by row: one value of each selected channel per row.
pub struct TdmsReader {
    source: String,
    input: Box<dyn ReadSeek>,
    file_len: u64,
    objects: Vec<Object>,
    by_path: HashMap<String, usize>,
    selected: Vec<Selected>,
    /// The object list of the last segment: (object, its index here).
    list: Vec<(usize, Option<Index>)>,
    /// Each object's last index.
    last_index: HashMap<usize, Index>,
    /// The next segment's offset (`None`: no more segments).
    next_segment: Option<u64>,
    layout: Option<Layout>,
    rows_read: u64,
    scratch: Vec<u8>,
}

impl std::fmt::Debug for TdmsReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TdmsReader")
            .field("source", &self.source)
            .field("channels", &self.channel_names())
            .field("rows_read", &self.rows_read)
            .finish()
    }
}

impl TdmsReader {
    /// Opens `path` and selects `channels` (see [`from_reader`](Self::from_reader)).
    pub fn open(path: &Path, channels: &[String], default_count: usize) -> Result<Self, IoError> {
        let source = path.display().to_string();
        let file = File::open(path).map_err(|e| IoError::Read {
            file: source.clone(),
            source: e,
        })?;
        Self::from_reader(
            &source,
            BufReader::with_capacity(1 << 16, file),
            channels,
            default_count,
        )
    }

    /// Reads the file's metadata from `input` and selects `channels`:
    /// `group/channel`, a channel name alone (unique in the file), or a
    /// TDMS path `/'group'/'channel'`. With none, the group holding channels
    /// `vx1, vx2, vy1, vy2` when `default_count` is 4 and one does, else the
    /// file's first `default_count` channels. `source` names the file in
    /// messages.
    pub fn from_reader(
        source: &str,
        input: impl Read + Seek + 'static,
        channels: &[String],
        default_count: usize,
    ) -> Result<Self, IoError> {
        let mut input: Box<dyn ReadSeek> = Box::new(input);
        let file_len = input
            .seek(SeekFrom::End(0))
            .map_err(|e| read_error(source, e))?;
        let mut reader = Self {
            source: source.to_string(),
            input,
            file_len,
            objects: Vec::new(),
            by_path: HashMap::new(),
            selected: Vec::new(),
            list: Vec::new(),
            last_index: HashMap::new(),
            next_segment: Some(0),
            layout: None,
            rows_read: 0,
            scratch: Vec::new(),
        };
        reader.catalogue()?;
        reader.select(channels, default_count)?;
        reader.next_segment = Some(0);
        Ok(reader)
    }

    fn error(&self, message: String) -> IoError {
        // Names come from the file: no control characters, a bounded line.
        let mut message: String = message
            .chars()
            .map(|c| if c.is_control() { '?' } else { c })
            .collect();
        if message.chars().count() > 400 {
            message = message.chars().take(400).collect::<String>() + "…";
        }
        IoError::Structure {
            at: Location::file(&self.source),
            message,
        }
    }

    /// The file, as named in messages.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The selected channels as `group/channel`.
    pub fn channel_names(&self) -> Vec<String> {
        self.selected.iter().map(|s| s.name.clone()).collect()
    }

    /// The selected channels' sample interval from their `wf_increment`
    /// property, s (`None` when none carries it); they must agree within
    /// `tolerance` (relative).
    pub fn increment_s(&self, tolerance: f64) -> Result<Option<f64>, IoError> {
        let mut found: Option<(f64, &str)> = None;
        for s in &self.selected {
            let Some(dt) = self.property(s.object, "wf_increment") else {
                continue;
            };
            if !(dt.is_finite() && dt > 0.0) {
                return Err(self.error(format!(
                    "channel {}: wf_increment {dt}; expected a positive sample interval, s",
                    s.name
                )));
            }
            match found {
                None => found = Some((dt, &s.name)),
                Some((first, name)) if (dt - first).abs() > tolerance * first => {
                    return Err(self.error(format!(
                        "channels {name} and {} have different sample intervals ({first} s, \
                         {dt} s); expected channels of one sample clock",
                        s.name
                    )))
                }
                Some(_) => {}
            }
        }
        Ok(found.map(|(dt, _)| dt))
    }

    /// Rows handed out so far.
    pub fn rows_read(&self) -> u64 {
        self.rows_read
    }

    fn property(&self, object: usize, name: &str) -> Option<f64> {
        match self.objects[object].properties.get(name) {
            Some(Value::Number(v)) => Some(*v),
            _ => None,
        }
    }

    /// Reads the next segment's lead-in and metadata; `None` at the end.
    fn segment(&mut self) -> Result<Option<(u64, LeadIn, Vec<MetaObject>)>, IoError> {
        let Some(start) = self.next_segment else {
            return Ok(None);
        };
        if start >= self.file_len {
            self.next_segment = None;
            return Ok(None);
        }
        if self.file_len - start < LEAD_IN {
            return Err(self.error(format!(
                "byte {start}: the file ends inside a segment's lead-in (truncated); expected \
                 whole segments"
            )));
        }
        let mut lead = [0u8; 28];
        self.input
            .seek(SeekFrom::Start(start))
            .and_then(|_| self.input.read_exact(&mut lead))
            .map_err(|e| read_error(&self.source, e))?;
        let lead_in = LeadIn::parse(&lead, start).map_err(|m| self.error(m))?;
        let body = start + LEAD_IN;
        let end = if lead_in.next_offset == UNFINISHED {
            self.file_len
        } else {
            body.checked_add(lead_in.next_offset)
                .filter(|&e| e <= self.file_len)
                .ok_or_else(|| {
                    self.error(format!(
                        "byte {start}: the segment announces {} bytes but the file ends at byte \
                         {} (truncated); expected whole segments",
                        lead_in.next_offset, self.file_len
                    ))
                })?
        };
        if lead_in.raw_offset > end - body {
            return Err(self.error(format!(
                "byte {}: the metadata ({} bytes) runs past the segment's end; expected a valid \
                 segment",
                start + 20,
                lead_in.raw_offset
            )));
        }
        let meta = if lead_in.has_meta() {
            if lead_in.raw_offset > MAX_METADATA {
                return Err(self.error(format!(
                    "byte {start}: {} bytes of metadata in one segment; expected at most {}",
                    lead_in.raw_offset, MAX_METADATA
                )));
            }
            let mut bytes = vec![0u8; lead_in.raw_offset as usize];
            self.input
                .read_exact(&mut bytes)
                .map_err(|e| read_error(&self.source, e))?;
            parse_metadata(&bytes, body, lead_in.big_endian()).map_err(|m| self.error(m))?
        } else {
            Vec::new()
        };
        self.next_segment =
            (lead_in.next_offset != UNFINISHED && end < self.file_len).then_some(end);
        Ok(Some((start, lead_in, meta)))
    }

    /// The first pass: every object and its properties.
    fn catalogue(&mut self) -> Result<(), IoError> {
        let mut property_bytes = 0usize;
        while let Some((start, _, meta)) = self.segment()? {
            for object in meta {
                let id = self.object_id(&object.path, start)?;
                for (name, value) in object.properties {
                    property_bytes += name.len()
                        + match &value {
                            Value::Text(t) => t.len(),
                            _ => 8,
                        };
                    if property_bytes > MAX_PROPERTY_BYTES {
                        return Err(self.error(format!(
                            "byte {start}: more than {MAX_PROPERTY_BYTES} bytes of properties; \
                             expected a recording's metadata"
                        )));
                    }
                    self.objects[id].properties.insert(name, value);
                }
            }
        }
        Ok(())
    }

    fn object_id(&mut self, path: &str, at: u64) -> Result<usize, IoError> {
        if let Some(&id) = self.by_path.get(path) {
            return Ok(id);
        }
        if self.objects.len() >= MAX_OBJECTS {
            return Err(self.error(format!(
                "byte {at}: more than {MAX_OBJECTS} objects; expected a recording's channels"
            )));
        }
        let id = self.objects.len();
        self.objects.push(Object {
            path: path.to_string(),
            properties: HashMap::new(),
        });
        self.by_path.insert(path.to_string(), id);
        Ok(id)
    }

    /// The file's channels in order: (object, group, channel).
    fn channel_list(&self) -> Vec<(usize, String, String)> {
        self.objects
            .iter()
            .enumerate()
            .filter_map(|(i, o)| channel_names(&o.path).map(|(g, c)| (i, g, c)))
            .collect()
    }

    fn select(&mut self, specs: &[String], default_count: usize) -> Result<(), IoError> {
        let all = self.channel_list();
        let listing = || {
            let names: Vec<String> = all.iter().map(|(_, g, c)| format!("{g}/{c}")).collect();
            excerpt(&names.join(", ")).to_string()
        };
        let mut chosen: Vec<(usize, String)> = Vec::new();
        if specs.is_empty() {
            let by_name = all.iter().find_map(|(_, g, _)| {
                let ids: Option<Vec<(usize, String)>> = TDMS_DEFAULT_CHANNELS
                    .iter()
                    .map(|n| {
                        all.iter()
                            .find(|(_, g2, c)| g2 == g && c == n)
                            .map(|(i, g, c)| (*i, format!("{g}/{c}")))
                    })
                    .collect();
                ids
            });
            match by_name {
                Some(ids) if default_count == 4 => chosen = ids,
                _ if all.len() >= default_count => {
                    chosen = all[..default_count]
                        .iter()
                        .map(|(i, g, c)| (*i, format!("{g}/{c}")))
                        .collect()
                }
                _ => {
                    return Err(self.error(format!(
                        "the file holds {} channels ({}); expected at least {default_count} \
                         (vx1, vx2, vy1, vy2 in one group), or name them",
                        all.len(),
                        listing()
                    )))
                }
            }
        } else {
            for spec in specs {
                let hits: Vec<&(usize, String, String)> = all
                    .iter()
                    .filter(|(i, g, c)| {
                        self.objects[*i].path == *spec
                            || *spec == format!("{g}/{c}")
                            || (!spec.contains('/') && c == spec)
                    })
                    .collect();
                match hits.as_slice() {
                    [(i, g, c)] => chosen.push((*i, format!("{g}/{c}"))),
                    [] => {
                        return Err(self.error(format!(
                            "no channel '{}' in the file; expected one of {}",
                            excerpt(spec),
                            listing()
                        )))
                    }
                    _ => {
                        return Err(self.error(format!(
                            "channel '{}' is in several groups; expected group/channel",
                            excerpt(spec)
                        )))
                    }
                }
            }
        }
        let mut selected = Vec::new();
        for (object, name) in chosen {
            let (group, _) = channel_names(&self.objects[object].path).unwrap_or_default();
            let sources = [
                Some(object),
                self.by_path.get(&group_path(&group)).copied(),
                self.by_path.get("/").copied(),
            ];
            let mut scaling = None;
            for props in sources
                .iter()
                .flatten()
                .map(|&o| &self.objects[o].properties)
            {
                if let Some(s) = Scaling::from_properties(props)
                    .map_err(|m| self.error(format!("channel {name}: {m}")))?
                {
                    scaling = Some(s);
                    break;
                }
            }
            selected.push(Selected {
                object,
                name,
                scaling,
            });
        }
        self.selected = selected;
        Ok(())
    }

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

fn read_error(source: &str, e: std::io::Error) -> IoError {
    IoError::Read {
        file: source.to_string(),
        source: e,
    }
}
