//! The bounded line reader under every CSV reader: physical lines, 1-based,
//! read one at a time from any `BufRead` (constant memory), each checked to
//! be text (no control byte, valid UTF-8) and at most
//! [`MAX_LINE_BYTES`] long, the whole input
//! optionally at most a number of bytes. Line ends are `\n` or `\r\n`; a
//! carriage return alone (old Mac line ends) is refused as such.
//! A reader of plain lines (raw.csv's numeric fast path) may take whole
//! lines straight from the buffer (`buffered`, `consume_lines`); the line
//! numbers and the byte count stay those of every line read.

use std::io::{BufRead, Read};

use crate::error::IoError;
use crate::limits::{bytes_text, too_large, MAX_LINE_BYTES};
use crate::location::Location;

/// Physical lines of a text input.
pub(crate) struct LineReader<R> {
    source: String,
    reader: R,
    /// The line number of the last line returned.
    line: usize,
    /// Bytes consumed so far.
    offset: u64,
    /// Largest input accepted, bytes (`None`: no limit).
    limit: Option<u64>,
    buf: Vec<u8>,
}

impl<R: BufRead> LineReader<R> {
    /// Lines of `reader`, named `source` in messages; `limit` bounds the
    /// whole input.
    pub fn new(source: &str, reader: R, limit: Option<u64>) -> Self {
        Self {
            source: source.to_string(),
            reader,
            line: 0,
            offset: 0,
            limit,
            buf: Vec::new(),
        }
    }

    /// The number of the last line read (0 before the first).
    pub fn line(&self) -> usize {
        self.line
    }

    /// The input's bytes that are already buffered after the last line read
    /// (reading more only when none are), at most up to the size limit, for
    /// a caller that reads whole plain lines itself and then
    /// [`consume_lines`](Self::consume_lines) them; empty before the first
    /// line (whose byte-order mark only [`next_line`](Self::next_line)
    /// handles); `None` at the end of the input.
    pub fn buffered(&mut self) -> Result<Option<&[u8]>, IoError> {
        if self.line == 0 {
            return Ok(Some(&[]));
        }
        let room = self.limit.map_or(usize::MAX, |limit| {
            usize::try_from(limit.saturating_sub(self.offset)).unwrap_or(usize::MAX)
        });
        let read_error = |source: &str, e| IoError::Read {
            file: source.to_string(),
            source: e,
        };
        // Filled once, retried when interrupted; the second call only
        // hands out what the first one buffered.
        loop {
            match self.reader.fill_buf() {
                Ok([]) => return Ok(None),
                Ok(_) => break,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(read_error(&self.source, e)),
            }
        }
        let bytes = self
            .reader
            .fill_buf()
            .map_err(|e| read_error(&self.source, e))?;
        Ok(Some(&bytes[..bytes.len().min(room)]))
    }

    /// Marks the first `bytes` bytes of [`buffered`](Self::buffered), which
    /// hold `lines` whole lines with their ends, as read.
    pub fn consume_lines(&mut self, bytes: usize, lines: usize) {
        self.reader.consume(bytes);
        self.offset += bytes as u64;
        self.line += lines;
    }

    /// The next line (its number and its text without the line end), or
    /// `None` at the end of the input.
    pub fn next_line(&mut self) -> Result<Option<(usize, &str)>, IoError> {
        self.buf.clear();
        let read = (&mut self.reader)
            .take(MAX_LINE_BYTES as u64 + 2)
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| IoError::Read {
                file: self.source.clone(),
                source: e,
            })?;
        if read == 0 {
            return Ok(None);
        }
        self.line += 1;
        let start = self.offset;
        self.offset += read as u64;
        if let Some(limit) = self.limit {
            if self.offset > limit {
                return Err(too_large(&self.source, limit));
            }
        }
        // Built only for an error (a String per line otherwise).
        let at = || Location::line(&self.source, self.line);
        let bom = if self.line == 1 && self.buf.starts_with(b"\xEF\xBB\xBF") {
            3
        } else {
            0
        };
        let base = start + bom as u64;
        let mut content: &[u8] = &self.buf[bom..];
        let ended = content.last() == Some(&b'\n');
        if ended {
            content = &content[..content.len() - 1];
        }
        content = content.strip_suffix(b"\r").unwrap_or(content);
        if content.len() > MAX_LINE_BYTES || (!ended && read > MAX_LINE_BYTES) {
            let hint = if content.contains(&b'\r') {
                " (its lines end with a carriage return alone, as on old Macs; save the file \
                 with LF or CRLF line ends)"
            } else {
                ""
            };
            return Err(IoError::Structure {
                at: at(),
                message: format!(
                    "the line is longer than {}; expected CSV lines of at most that length{hint}",
                    bytes_text(MAX_LINE_BYTES as u64)
                ),
            });
        }
        if let Some(pos) = content
            .iter()
            .position(|&b| (b < 0x20 && !matches!(b, b'\t' | b'\r')) || b == 0x7f)
        {
            let byte = content[pos];
            return Err(IoError::Encoding {
                at: at(),
                message: format!(
                    "binary data (control byte 0x{byte:02x} at byte offset {}); expected a \
                     UTF-8 CSV text file",
                    base + pos as u64
                ),
            });
        }
        if content.contains(&b'\r') {
            return Err(IoError::Structure {
                at: at(),
                message: "a carriage return alone ends a line (old Mac line ends); expected \
                          LF or CRLF line ends: save the file with them"
                    .to_string(),
            });
        }
        match std::str::from_utf8(content) {
            Ok(text) => Ok(Some((self.line, text))),
            Err(e) => {
                let pos = e.valid_up_to();
                let byte = content.get(pos).copied().unwrap_or(0);
                Err(IoError::Encoding {
                    at: at(),
                    message: format!(
                        "byte 0x{byte:02x} at byte offset {} is not UTF-8; expected UTF-8 text",
                        base + pos as u64
                    ),
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(bytes: &[u8]) -> Result<Vec<(usize, String)>, IoError> {
        let mut r = LineReader::new("t.csv", bytes, None);
        let mut out = Vec::new();
        while let Some((n, text)) = r.next_line()? {
            out.push((n, text.to_string()));
        }
        Ok(out)
    }

    #[test]
    fn line_ends_bom_and_numbers() {
        let got = lines(b"\xEF\xBB\xBFa,b\r\n\n1,2").unwrap();
        assert_eq!(
            got,
            vec![(1, "a,b".into()), (2, String::new()), (3, "1,2".into())]
        );
    }

    #[test]
    fn long_lines_and_cr_only_files_are_refused_briefly() {
        let long = vec![b'x'; MAX_LINE_BYTES + 10];
        let e = lines(&long).unwrap_err();
        assert_eq!(e.line(), Some(1));
        assert!(e.to_string().contains("longer than 1 MiB"), "{e}");
        let mut cr = b"a,b\r".to_vec();
        for _ in 0..(MAX_LINE_BYTES / 4) {
            cr.extend_from_slice(b"1,2\r");
        }
        let e = lines(&cr).unwrap_err();
        assert!(e.to_string().contains("carriage return alone"), "{e}");
        assert!(e.to_string().len() < 300, "{e}");
        let e = lines(b"a,b\r1,2\r").unwrap_err();
        assert!(e.to_string().contains("carriage return alone"), "{e}");
    }

    #[test]
    fn binary_offsets_and_size_limit() {
        let e = lines(b"a,b\n1,\x002\n").unwrap_err();
        assert_eq!(e.line(), Some(2));
        assert!(e.to_string().contains("0x00 at byte offset 6"), "{e}");
        let e = lines(b"\xEF\xBB\xBFa,\xe9\n").unwrap_err();
        assert!(e.to_string().contains("0xe9 at byte offset 5"), "{e}");
        let mut r = LineReader::new(
            "z",
            std::io::BufReader::new(std::io::repeat(b'\n')),
            Some(100),
        );
        let e = loop {
            match r.next_line() {
                Ok(Some(_)) => {}
                Ok(None) => panic!("endless input ended"),
                Err(e) => break e,
            }
        };
        assert!(matches!(e, IoError::TooLarge { .. }), "{e}");
    }
}
