//! NI TDMS recordings read as a stream of rows of selected channels
//! (docs/formats.md, "Raw recordings", raw.tdms), in bounded memory
//! whatever the file size. The segment structure is in `tdms_meta.rs`; the
//! streaming of the raw data (each segment's layout, the rows) in
//! `tdms/stream.rs`.
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

use crate::error::IoError;
use crate::limits::excerpt;
use crate::location::Location;
use crate::tdms_meta::{
    channel_names, group_path, parse_metadata, Index, LeadIn, MetaObject, Value, LEAD_IN,
    UNFINISHED,
};
use crate::tdms_scaling::Scaling;

mod stream;

use stream::Layout;

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
}

fn read_error(source: &str, e: std::io::Error) -> IoError {
    IoError::Read {
        file: source.to_string(),
        source: e,
    }
}
