//! raw.tdms as psdcal writes it (`simulate --raw tdms`; the layout of
//! `tdms_meta.rs`): little-endian, contiguous float64 channels `vx1`, `vx2`,
//! `vy1`, `vy2` in the group `psd`, each with `wf_increment = 1/rate` and
//! `unit_string = V`. The first block of frames is a segment with the
//! metadata (a new object list); each later block is a segment of raw data
//! only when it holds as many frames as the previous one, else a segment
//! whose incremental metadata gives the channels their new value count.
//!
//! A rig's recording ([`TdmsFrameWriter::with_groups`]): one group per
//! sensor, named by its id, each with the channels `vx1` … `vy2`; rows of
//! `4 S` values, the sensors in the groups' order.

use crate::raw_frame::Frame;

const TOC_META: u32 = 1 << 1;
const TOC_NEW_LIST: u32 = 1 << 2;
const TOC_RAW: u32 = 1 << 3;
/// tdsTypeDoubleFloat, tdsTypeString.
const F64: u32 = 10;
const STRING: u32 = 0x20;

/// Writes frames as TDMS segments, block by block.
#[derive(Debug, Clone)]
pub struct TdmsFrameWriter {
    rate_hz: f64,
    groups: Vec<String>,
    last_count: Option<usize>,
}

fn string(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(&(s.len() as u32).to_le_bytes());
    out.extend_from_slice(s.as_bytes());
}

impl TdmsFrameWriter {
    /// A writer of a recording sampled at `rate_hz`.
    pub fn new(rate_hz: f64) -> Self {
        Self::with_groups(rate_hz, vec!["psd".to_string()])
    }

    /// A writer of a rig's recording: one group of four channels per name
    /// in `groups` (TDMS quotes in names doubled).
    pub fn with_groups(rate_hz: f64, groups: Vec<String>) -> Self {
        Self {
            rate_hz,
            groups: groups.iter().map(|g| g.replace('\'', "''")).collect(),
            last_count: None,
        }
    }

    /// Writes `frames` as one segment (nothing for no frames).
    pub fn write(&mut self, w: &mut impl std::io::Write, frames: &[Frame]) -> std::io::Result<()> {
        let rows: Vec<f64> = frames.iter().flatten().copied().collect();
        self.write_rows(w, &rows)
    }

    /// Writes rows of `4 G` values (`G` groups, each `vx1, vx2, vy1, vy2`)
    /// as one segment (nothing for no rows; a partial row is ignored).
    pub fn write_rows(&mut self, w: &mut impl std::io::Write, rows: &[f64]) -> std::io::Result<()> {
        let width = 4 * self.groups.len();
        let n = rows.len() / width;
        if n == 0 {
            return Ok(());
        }
        let paths: Vec<String> = self
            .groups
            .iter()
            .flat_map(|g| {
                crate::tdms::TDMS_DEFAULT_CHANNELS
                    .iter()
                    .map(move |c| format!("/'{g}'/'{c}'"))
            })
            .collect();
        let mut meta = Vec::new();
        let toc = match self.last_count {
            None => {
                let objects = 1 + self.groups.len() + paths.len();
                meta.extend_from_slice(&(objects as u32).to_le_bytes());
                string(&mut meta, "/");
                meta.extend_from_slice(&u32::MAX.to_le_bytes());
                meta.extend_from_slice(&0u32.to_le_bytes());
                for g in &self.groups {
                    string(&mut meta, &format!("/'{g}'"));
                    meta.extend_from_slice(&u32::MAX.to_le_bytes());
                    meta.extend_from_slice(&0u32.to_le_bytes());
                }
                for path in &paths {
                    string(&mut meta, path);
                    index(&mut meta, n);
                    meta.extend_from_slice(&2u32.to_le_bytes());
                    string(&mut meta, "wf_increment");
                    meta.extend_from_slice(&F64.to_le_bytes());
                    meta.extend_from_slice(&(1.0 / self.rate_hz).to_le_bytes());
                    string(&mut meta, "unit_string");
                    meta.extend_from_slice(&STRING.to_le_bytes());
                    string(&mut meta, "V");
                }
                TOC_META | TOC_NEW_LIST | TOC_RAW
            }
            Some(last) if last == n => TOC_RAW,
            Some(_) => {
                meta.extend_from_slice(&(paths.len() as u32).to_le_bytes());
                for path in &paths {
                    string(&mut meta, path);
                    index(&mut meta, n);
                    meta.extend_from_slice(&0u32.to_le_bytes());
                }
                TOC_META | TOC_RAW
            }
        };
        self.last_count = Some(n);
        let data = (n * width * 8) as u64;
        w.write_all(b"TDSm")?;
        w.write_all(&toc.to_le_bytes())?;
        w.write_all(&4713u32.to_le_bytes())?;
        w.write_all(&(meta.len() as u64 + data).to_le_bytes())?;
        w.write_all(&(meta.len() as u64).to_le_bytes())?;
        w.write_all(&meta)?;
        let mut buf = Vec::with_capacity(n * 8);
        for c in 0..width {
            buf.clear();
            for row in rows.chunks_exact(width) {
                buf.extend_from_slice(&row[c].to_le_bytes());
            }
            w.write_all(&buf)?;
        }
        Ok(())
    }
}

/// A raw data index of `n` float64 values.
fn index(meta: &mut Vec<u8>, n: usize) {
    meta.extend_from_slice(&20u32.to_le_bytes());
    meta.extend_from_slice(&F64.to_le_bytes());
    meta.extend_from_slice(&1u32.to_le_bytes());
    meta.extend_from_slice(&(n as u64).to_le_bytes());
}
