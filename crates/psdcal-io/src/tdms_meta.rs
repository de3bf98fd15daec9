//! The structure of an NI TDMS segment (docs/formats.md, "Raw recordings",
//! raw.tdms), as NI publishes it: a 28-byte lead-in, the metadata (objects
//! with their raw data index and properties), then the raw data.
//!
//! - **Lead-in**: the tag `TDSm`; the table-of-contents mask (a
//!   little-endian `u32`: bit 1 metadata, 2 new object list, 3 raw data,
//!   5 interleaved, 6 big-endian, 7 DAQmx raw data); the version `u32`
//!   (4712 or 4713); the offset of the next segment and of the raw data,
//!   both `u64` counted from the end of the lead-in (all ones: a segment the
//!   writer never finished). Everything after the mask is in the segment's
//!   byte order (bit 6).
//! - **Metadata**: `u32` object count; per object its path (a `u32`
//!   length and UTF-8 bytes: `/`, `/'group'`, `/'group'/'channel'`, a quote
//!   doubled inside a name), its raw data index (`u32` `0xFFFFFFFF`: no
//!   data here; `0`: the same index as in the previous segment;
//!   `0x69120000`, `0x69130000`: DAQmx, not read; otherwise the index's
//!   length, 20 or 28, then the data type `u32`, the dimension `u32` (1),
//!   the number of values `u64` and, for strings, their total bytes `u64`),
//!   then `u32` property count and per property a name string, a type `u32`
//!   and the value.
//!
//! Every failure is a message naming the absolute byte offset; the reader
//! (`tdms.rs`) puts the file's name before it.

/// Bytes of a segment's lead-in.
pub(crate) const LEAD_IN: u64 = 28;
/// The `next segment offset` of a segment the writer never finished.
pub(crate) const UNFINISHED: u64 = u64::MAX;

const TOC_META: u32 = 1 << 1;
const TOC_NEW_LIST: u32 = 1 << 2;
const TOC_RAW: u32 = 1 << 3;
const TOC_INTERLEAVED: u32 = 1 << 5;
const TOC_BIG_ENDIAN: u32 = 1 << 6;
const TOC_DAQMX: u32 = 1 << 7;

/// A segment's lead-in.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LeadIn {
    toc: u32,
    /// Bytes from the end of the lead-in to the next segment.
    pub next_offset: u64,
    /// Bytes from the end of the lead-in to the raw data (the metadata's size).
    pub raw_offset: u64,
}

impl LeadIn {
    /// Parses the 28 bytes at absolute offset `at`.
    pub fn parse(b: &[u8; 28], at: u64) -> Result<Self, String> {
        if &b[..4] != b"TDSm" {
            return Err(format!(
                "byte {at}: no segment tag 'TDSm' (found {:?}); expected an NI TDMS file \
                 (not its .tdms_index)",
                String::from_utf8_lossy(&b[..4])
                    .chars()
                    .map(|c| if c.is_control() { '?' } else { c })
                    .collect::<String>()
            ));
        }
        let toc = u32::from_le_bytes([b[4], b[5], b[6], b[7]]);
        let big = toc & TOC_BIG_ENDIAN != 0;
        let mut c = Bytes::new(&b[8..], at + 8, big);
        let version = c.u32()?;
        if version != 4712 && version != 4713 {
            return Err(format!(
                "byte {}: TDMS version {version}; expected 4712 or 4713",
                at + 8
            ));
        }
        let next_offset = c.u64()?;
        let raw_offset = c.u64()?;
        if next_offset != UNFINISHED && raw_offset > next_offset {
            return Err(format!(
                "byte {}: the raw data offset {raw_offset} lies past the next segment \
                 ({next_offset}); expected a valid segment",
                at + 20
            ));
        }
        Ok(Self {
            toc,
            next_offset,
            raw_offset,
        })
    }
    /// Metadata present.
    pub fn has_meta(&self) -> bool {
        self.toc & TOC_META != 0
    }
    /// The object list starts anew.
    pub fn new_list(&self) -> bool {
        self.toc & TOC_NEW_LIST != 0
    }
    /// Raw data present.
    pub fn has_raw(&self) -> bool {
        self.toc & (TOC_RAW | TOC_DAQMX) != 0
    }
    /// DAQmx raw data.
    pub fn daqmx(&self) -> bool {
        self.toc & TOC_DAQMX != 0
    }
    /// Channels' values interleaved.
    pub fn interleaved(&self) -> bool {
        self.toc & TOC_INTERLEAVED != 0
    }
    /// Big-endian metadata and data.
    pub fn big_endian(&self) -> bool {
        self.toc & TOC_BIG_ENDIAN != 0
    }
}

/// A TDMS data type (the codes NI publishes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum DataType {
    /// Signed and unsigned integers, 1–8 bytes.
    Int { bytes: u8, signed: bool },
    /// IEEE float, 4 or 8 bytes (also the "with unit" codes).
    Float { bytes: u8 },
    /// Not a number psdcal reads as samples (extended float, boolean,
    /// timestamp, complex, fixed point, void): its size in bytes.
    Other { bytes: u8, name: &'static str },
    /// Strings (variable size).
    Text,
    /// DAQmx raw data.
    Daqmx,
}

impl DataType {
    /// The type of `code`.
    pub fn from_code(code: u32) -> Option<Self> {
        use DataType::*;
        Some(match code {
            0 => Other {
                bytes: 0,
                name: "void",
            },
            1 => Int {
                bytes: 1,
                signed: true,
            },
            2 => Int {
                bytes: 2,
                signed: true,
            },
            3 => Int {
                bytes: 4,
                signed: true,
            },
            4 => Int {
                bytes: 8,
                signed: true,
            },
            5 => Int {
                bytes: 1,
                signed: false,
            },
            6 => Int {
                bytes: 2,
                signed: false,
            },
            7 => Int {
                bytes: 4,
                signed: false,
            },
            8 => Int {
                bytes: 8,
                signed: false,
            },
            9 | 0x19 => Float { bytes: 4 },
            10 | 0x1A => Float { bytes: 8 },
            11 | 0x1B => Other {
                bytes: 16,
                name: "extended float",
            },
            0x20 => Text,
            0x21 => Other {
                bytes: 1,
                name: "boolean",
            },
            0x44 => Other {
                bytes: 16,
                name: "timestamp",
            },
            0x4F => Other {
                bytes: 8,
                name: "fixed point",
            },
            0x08000c => Other {
                bytes: 8,
                name: "complex float32",
            },
            0x10000d => Other {
                bytes: 16,
                name: "complex float64",
            },
            0xFFFF_FFFF => Daqmx,
            _ => return None,
        })
    }

    /// Bytes of one value (`None`: strings, DAQmx).
    pub fn size(self) -> Option<u64> {
        match self {
            DataType::Int { bytes, .. }
            | DataType::Float { bytes }
            | DataType::Other { bytes, .. } => Some(bytes as u64),
            DataType::Text | DataType::Daqmx => None,
        }
    }

    /// Whether psdcal reads this type as samples.
    pub fn is_sample(self) -> bool {
        matches!(self, DataType::Int { .. } | DataType::Float { .. })
    }

    /// A name for messages.
    pub fn name(self) -> &'static str {
        match self {
            DataType::Int { .. } => "integer",
            DataType::Float { .. } => "float",
            DataType::Other { name, .. } => name,
            DataType::Text => "string",
            DataType::Daqmx => "DAQmx raw",
        }
    }

    /// Decodes one value (`b` holds exactly [`size`](Self::size) bytes).
    pub fn decode(self, b: &[u8], big: bool) -> f64 {
        macro_rules! num {
            ($t:ty) => {{
                let mut a = [0u8; std::mem::size_of::<$t>()];
                a.copy_from_slice(b);
                if big {
                    <$t>::from_be_bytes(a) as f64
                } else {
                    <$t>::from_le_bytes(a) as f64
                }
            }};
        }
        match self {
            DataType::Int { bytes: 1, signed } => {
                if signed {
                    b[0] as i8 as f64
                } else {
                    b[0] as f64
                }
            }
            DataType::Int {
                bytes: 2,
                signed: true,
            } => num!(i16),
            DataType::Int {
                bytes: 2,
                signed: false,
            } => num!(u16),
            DataType::Int {
                bytes: 4,
                signed: true,
            } => num!(i32),
            DataType::Int {
                bytes: 4,
                signed: false,
            } => num!(u32),
            DataType::Int {
                bytes: 8,
                signed: true,
            } => num!(i64),
            DataType::Int {
                bytes: 8,
                signed: false,
            } => num!(u64),
            DataType::Float { bytes: 4 } => num!(f32),
            DataType::Float { bytes: 8 } => num!(f64),
            _ => f64::NAN,
        }
    }
}

/// An object's raw data index in one segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Index {
    /// The values' type.
    pub dtype: DataType,
    /// Values per chunk.
    pub count: u64,
    /// Bytes per chunk.
    pub bytes: u64,
}

/// What a segment's metadata says about an object's raw data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RawIndex {
    /// No raw data in this segment.
    NoData,
    /// The same index as in the previous segment.
    Same,
    /// A new index.
    New(Index),
}

/// A property value, as far as psdcal uses it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Value {
    /// Any number (integers, floats, booleans as 0/1).
    Number(f64),
    /// A string.
    Text(String),
    /// Something else (timestamps, complex numbers…).
    Other,
}

/// One object of a segment's metadata.
#[derive(Debug, Clone)]
pub(crate) struct MetaObject {
    /// Its path, e.g. `/'group'/'channel'`.
    pub path: String,
    /// Its raw data index here.
    pub index: RawIndex,
    /// Its properties set in this segment.
    pub properties: Vec<(String, Value)>,
}

/// Bytes read in a byte order, with absolute offsets for messages.
struct Bytes<'a> {
    b: &'a [u8],
    pos: usize,
    base: u64,
    big: bool,
}

impl<'a> Bytes<'a> {
    fn new(b: &'a [u8], base: u64, big: bool) -> Self {
        Self {
            b,
            pos: 0,
            base,
            big,
        }
    }
    fn at(&self) -> u64 {
        self.base + self.pos as u64
    }
    fn take(&mut self, n: u64) -> Result<&'a [u8], String> {
        let left = (self.b.len() - self.pos) as u64;
        if n > left {
            return Err(format!(
                "byte {}: the metadata ends inside a value ({n} bytes wanted, {left} left); \
                 expected a whole TDMS segment",
                self.at()
            ));
        }
        let s = &self.b[self.pos..self.pos + n as usize];
        self.pos += n as usize;
        Ok(s)
    }
    fn u32(&mut self) -> Result<u32, String> {
        let s = self.take(4)?;
        let a = [s[0], s[1], s[2], s[3]];
        Ok(if self.big {
            u32::from_be_bytes(a)
        } else {
            u32::from_le_bytes(a)
        })
    }
    fn u64(&mut self) -> Result<u64, String> {
        let s = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(s);
        Ok(if self.big {
            u64::from_be_bytes(a)
        } else {
            u64::from_le_bytes(a)
        })
    }
    fn string(&mut self) -> Result<String, String> {
        let at = self.at();
        let n = self.u32()?;
        let s = self.take(n as u64)?;
        String::from_utf8(s.to_vec())
            .map_err(|_| format!("byte {at}: a name or text that is not UTF-8"))
    }
}

/// Parses a segment's metadata, `b`, which starts at absolute offset `base`.
pub(crate) fn parse_metadata(b: &[u8], base: u64, big: bool) -> Result<Vec<MetaObject>, String> {
    let mut c = Bytes::new(b, base, big);
    let n = c.u32()?;
    // Each object takes at least 12 bytes: a bounded count.
    if n as u64 * 12 > b.len() as u64 {
        return Err(format!(
            "byte {base}: {n} objects announced in {} bytes of metadata; expected a valid segment",
            b.len()
        ));
    }
    let mut objects = Vec::with_capacity(n as usize);
    for _ in 0..n {
        let path = c.string()?;
        let label = crate::limits::excerpt(&path).to_string();
        let index_at = c.at();
        let head = c.u32()?;
        let index = match head {
            0xFFFF_FFFF => RawIndex::NoData,
            0 => RawIndex::Same,
            0x6912_0000 | 0x6913_0000 => {
                return Err(format!(
                    "byte {index_at}: channel {label} holds DAQmx raw data, which psdcal does not \
                     read; expected scaled values (log with DAQmx's 'log and read' mode, or \
                     convert, e.g. with npTDMS, to .npy)"
                ))
            }
            20 | 28 => {
                let code = c.u32()?;
                let dtype = DataType::from_code(code).ok_or_else(|| {
                    format!(
                        "byte {}: unknown data type {code:#x} of {label}",
                        index_at + 4
                    )
                })?;
                let dim = c.u32()?;
                if dim != 1 {
                    return Err(format!(
                        "byte {}: array dimension {dim} of {label}; expected 1",
                        index_at + 8
                    ));
                }
                let count = c.u64()?;
                let bytes = match (dtype, head) {
                    (DataType::Text, 28) => c.u64()?,
                    (DataType::Text, _) | (_, 28) => {
                        return Err(format!(
                            "byte {index_at}: a raw data index of {head} bytes for {} values; \
                             expected 28 for strings, 20 otherwise",
                            dtype.name()
                        ))
                    }
                    (dtype, _) => {
                        dtype
                            .size()
                            .and_then(|s| s.checked_mul(count))
                            .ok_or_else(|| {
                                format!("byte {index_at}: {count} values of {label} overflow")
                            })?
                    }
                };
                RawIndex::New(Index {
                    dtype,
                    count,
                    bytes,
                })
            }
            other => {
                return Err(format!(
                    "byte {index_at}: raw data index {other:#x} of {label}; expected 0xFFFFFFFF, \
                     0, 20 or 28"
                ))
            }
        };
        let np = c.u32()?;
        if np as u64 * 12 > (b.len() - c.pos) as u64 {
            return Err(format!(
                "byte {}: {np} properties announced for {label} in the bytes left; expected a \
                 valid segment",
                c.at()
            ));
        }
        let mut properties = Vec::with_capacity(np as usize);
        for _ in 0..np {
            let name = c.string()?;
            let label = crate::limits::excerpt(&name).to_string();
            let type_at = c.at();
            let code = c.u32()?;
            let dtype = DataType::from_code(code).ok_or_else(|| {
                format!("byte {type_at}: unknown type {code:#x} of property {label}")
            })?;
            let value = match dtype {
                DataType::Text => Value::Text(c.string()?),
                DataType::Int { .. } | DataType::Float { .. } => {
                    let size = dtype.size().unwrap_or(0);
                    Value::Number(dtype.decode(c.take(size)?, big))
                }
                DataType::Other { bytes: 1, .. } => Value::Number(f64::from(c.take(1)?[0] != 0)),
                DataType::Other { bytes, .. } => {
                    c.take(bytes as u64)?;
                    Value::Other
                }
                DataType::Daqmx => {
                    return Err(format!(
                        "byte {type_at}: property {label} of DAQmx type; expected a plain value"
                    ))
                }
            };
            properties.push((name, value));
        }
        objects.push(MetaObject {
            path,
            index,
            properties,
        });
    }
    Ok(objects)
}

/// The group and channel names of a path `/'group'/'channel'` (`None` for
/// the root or a group).
pub(crate) fn channel_names(path: &str) -> Option<(String, String)> {
    let mut names = Vec::new();
    let mut rest = path.strip_prefix('/')?;
    while !rest.is_empty() {
        let mut chars = rest.strip_prefix('\'')?.char_indices().peekable();
        let mut name = String::new();
        let end = loop {
            let (i, ch) = chars.next()?;
            if ch == '\'' {
                if chars.peek().map(|&(_, c)| c) == Some('\'') {
                    chars.next();
                    name.push('\'');
                    continue;
                }
                break i + 1;
            }
            name.push(ch);
        };
        names.push(name);
        rest = &rest[1 + end..];
        rest = rest.strip_prefix('/').unwrap_or(rest);
    }
    match <[String; 2]>::try_from(names) {
        Ok([g, c]) => Some((g, c)),
        Err(_) => None,
    }
}

/// The path of a group's or a channel's parent objects: `/'group'` of
/// `/'group'/'channel'`, `/` of a group.
pub(crate) fn group_path(group: &str) -> String {
    format!("/'{}'", group.replace('\'', "''"))
}
