//! The numeric fast path of a streamed CSV table (raw.csv): a line of plain
//! numbers read straight from the input's buffered bytes, with no copy and
//! no allocation per line or field.
//!
//! A line is taken here only when the general reader (`csv_lines`,
//! `csv_fields`, `csv_table`) would read it to the same values without an
//! error; every other line is left to the general reader, which gives the
//! value or the error with its line and column. The fast path therefore
//! changes the speed and nothing else. A *plain line* is:
//!
//! - ASCII, ending in `\n` or `\r\n`, at most
//!   [`MAX_LINE_BYTES`] long without its end;
//! - exactly as many comma-separated fields as the header;
//! - each wanted field: blanks (space, tab), a number token, blanks; every
//!   other field printable ASCII or tabs without `"`;
//! - not a comment (its first non-blank byte is not `#`).
//!
//! Blank and comment lines, quotes, other whitespace, non-ASCII text, a
//! field too many or too few, and a value that is not a finite number all
//! fall outside, and so does a line that does not end within the bytes
//! given (the end of a buffer).
//!
//! **Numbers.** A token `[+-]digits[.digits][(e|E)[+-]digits]` whose
//! significant digits form an integer `w ≤ 2^53` and whose value is
//! `w × 10^q` with `|q| ≤ 22` (at most four exponent digits) is computed
//! as one IEEE multiplication or division of two exactly representable
//! `f64` (`w` and `10^|q|`), hence correctly rounded (Clinger's fast
//! path); `str::parse::<f64>` returns the correctly rounded value too, so
//! both agree to the bit. The digits are read eight at a time once the
//! significant ones have begun. Every other token (more digits, larger
//! exponents) goes to `str::parse::<f64>` itself. A value that is not
//! finite leaves the line to the general reader.

use crate::limits::MAX_LINE_BYTES;

/// `10^k` for `k = 0..=22`: every one exact in `f64`.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// The largest integer below which every integer is exact in `f64`.
const EXACT_INTEGER: u64 = 1 << 53;

/// A column that is read past.
const SKIPPED: u8 = u8::MAX;

/// Which columns of a table's lines are wanted as numbers.
#[derive(Debug, Clone)]
pub(crate) struct NumericLine {
    /// Per header column, the slot its value goes to, or [`SKIPPED`].
    slots: Vec<u8>,
}

impl NumericLine {
    /// Lines of `columns` fields whose columns `wanted[k]` (0-based, at most
    /// 254 of them, each once) go to slot `k`.
    pub fn new(columns: usize, wanted: &[usize]) -> Self {
        let mut slots = vec![SKIPPED; columns];
        for (slot, &column) in wanted.iter().enumerate() {
            slots[column] = u8::try_from(slot).unwrap_or(SKIPPED);
        }
        Self { slots }
    }

    /// Reads the plain line at the start of `bytes`, its wanted values into
    /// `values` (one slot each); returns the line's length with its end, or
    /// `None` when the line is not plain (see the module's documentation)
    /// or does not end within `bytes`: the general reader then takes it.
    #[inline]
    pub fn parse(&self, bytes: &[u8], values: &mut [f64]) -> Option<usize> {
        let blank = |b: u8| b == b' ' || b == b'\t';
        let mut i = 0;
        let last = self.slots.len().checked_sub(1)?;
        for (column, &slot) in self.slots.iter().enumerate() {
            if slot == SKIPPED {
                if column == 0 {
                    let first = bytes.iter().position(|&b| !blank(b))?;
                    if bytes[first] == b'#' {
                        return None;
                    }
                }
                loop {
                    let b = *bytes.get(i)?;
                    if matches!(b, b',' | b'\n' | b'\r') {
                        break;
                    }
                    if !(b == b'\t' || (0x20..0x7f).contains(&b)) || b == b'"' {
                        return None;
                    }
                    i += 1;
                }
            } else {
                while blank(*bytes.get(i)?) {
                    i += 1;
                }
                let (value, end) = number_at(bytes, i)?;
                i = end;
                while blank(*bytes.get(i)?) {
                    i += 1;
                }
                *values.get_mut(usize::from(slot))? = value;
            }
            let b = *bytes.get(i)?;
            if column < last {
                if b != b',' {
                    return None;
                }
                i += 1;
                continue;
            }
            if i > MAX_LINE_BYTES {
                return None;
            }
            return match (b, bytes.get(i + 1)) {
                (b'\n', _) => Some(i + 1),
                (b'\r', Some(b'\n')) => Some(i + 2),
                _ => None,
            };
        }
        None
    }
}

/// A byte that can be part of a number token here.
#[inline]
fn number_byte(b: u8) -> bool {
    b.is_ascii_digit() || matches!(b, b'.' | b'+' | b'-' | b'e' | b'E')
}

/// The finite value of a number token, as `str::parse::<f64>` reads it;
/// `None` for anything else (empty, not a number, not finite).
#[cfg(test)]
fn finite_number(token: &[u8]) -> Option<f64> {
    number_at(token, 0)
        .filter(|&(_, end)| end == token.len())
        .map(|(value, _)| value)
}

/// The number token at `bytes[start..]` (the longest run of
/// [`number_byte`]s): its value as `str::parse::<f64>` reads the token, and
/// the index after it; `None` when it is not a finite number.
#[inline]
fn number_at(bytes: &[u8], start: usize) -> Option<(f64, usize)> {
    if let Some((value, end)) = exact_prefix(bytes, start) {
        if !bytes.get(end).is_some_and(|&b| number_byte(b)) {
            return Some((value, end));
        }
    }
    let mut end = start;
    while bytes.get(end).is_some_and(|&b| number_byte(b)) {
        end += 1;
    }
    let value = std::str::from_utf8(&bytes[start..end])
        .ok()?
        .parse::<f64>()
        .ok()?;
    value.is_finite().then_some((value, end))
}

/// An optional sign at `s[*i]`, stepped over: whether it is `-`.
#[inline]
fn sign(s: &[u8], i: &mut usize) -> bool {
    match s.get(*i) {
        Some(b'-') => {
            *i += 1;
            true
        }
        Some(b'+') => {
            *i += 1;
            false
        }
        _ => false,
    }
}

/// The value of `[+-]digits[.digits][(e|E)[+-]digits]` at `s[start..]`
/// and the index after it, when Clinger's fast path gives it exactly
/// rounded (significant digits `w ≤ 2^53`, value `w × 10^q` with
/// `|q| ≤ 22`, at most 4 exponent digits); `None` otherwise.
#[inline]
fn exact_prefix(s: &[u8], start: usize) -> Option<(f64, usize)> {
    let mut i = start;
    let negative = sign(s, &mut i);
    let mut w: u64 = 0;
    let mut significant = 0u32;
    let integer_digits = digits(s, &mut i, &mut w, &mut significant)?;
    let mut scale: i64 = 0;
    let mut fraction_digits = 0;
    if s.get(i) == Some(&b'.') {
        i += 1;
        fraction_digits = digits(s, &mut i, &mut w, &mut significant)?;
        scale = -i64::try_from(fraction_digits).ok()?;
    }
    if integer_digits + fraction_digits == 0 {
        return None;
    }
    if matches!(s.get(i), Some(b'e' | b'E')) {
        i += 1;
        let exponent_negative = sign(s, &mut i);
        let mut exponent = 0i64;
        let first = i;
        while let Some(&b) = s.get(i).filter(|b| b.is_ascii_digit()) {
            if i - first == 4 {
                return None;
            }
            exponent = exponent * 10 + i64::from(b - b'0');
            i += 1;
        }
        if i == first {
            return None;
        }
        scale += if exponent_negative {
            -exponent
        } else {
            exponent
        };
    }
    if w > EXACT_INTEGER {
        return None;
    }
    let magnitude = w as f64;
    let value = match scale {
        0 => magnitude,
        1..=22 => magnitude * POW10[scale as usize],
        -22..=-1 => magnitude / POW10[(-scale) as usize],
        _ => return None,
    };
    Some((if negative { -value } else { value }, i))
}

/// Reads the decimal digits at `s[*i..]` into `w` (`w · 10 + d` each),
/// counting the significant ones (leading zeros do not count); returns how
/// many digits, or `None` past 19 significant digits (`w` would overflow).
#[inline(always)]
fn digits(s: &[u8], i: &mut usize, w: &mut u64, significant: &mut u32) -> Option<usize> {
    let start = *i;
    loop {
        // Eight at a time once the significant digits have begun.
        if *w != 0 && *significant <= 11 {
            if let Some(v) = s.get(*i..*i + 8).and_then(eight_digits) {
                *w = *w * 100_000_000 + v;
                *significant += 8;
                *i += 8;
                continue;
            }
        }
        match s.get(*i) {
            Some(&b) if b.is_ascii_digit() => {
                let d = u64::from(b - b'0');
                if *w != 0 || d != 0 {
                    *significant += 1;
                    if *significant > 19 {
                        return None;
                    }
                }
                *w = *w * 10 + d;
                *i += 1;
            }
            _ => return Some(*i - start),
        }
    }
}

/// The value of eight ASCII decimal digits (the first the most
/// significant), or `None` when one of the bytes is not a digit: the digits
/// combined pairwise in one 64-bit word (SWAR: two, then four, then eight).
#[inline(always)]
fn eight_digits(bytes: &[u8]) -> Option<u64> {
    let word = u64::from_le_bytes(bytes.try_into().ok()?);
    // Every byte 0x30..=0x39: its high half is 3, and still 3 after adding 6.
    let high = 0xF0F0_F0F0_F0F0_F0F0_u64;
    let threes = 0x3333_3333_3333_3333_u64;
    let sixes = 0x0606_0606_0606_0606_u64;
    if (word & high) | ((word.wrapping_add(sixes) & high) >> 4) != threes {
        return None;
    }
    // Bytes d0..d7 (d0 first in the text, in the lowest byte).
    let d = word - 0x3030_3030_3030_3030;
    // Byte 2k: 10 d_2k + d_2k+1.
    let pairs = d.wrapping_mul(10).wrapping_add(d >> 8);
    // Bytes 0 and 4 weighted 10^6 and 100, bytes 2 and 6 10^4 and 1: the
    // sum lands in the upper half.
    let mask = 0x0000_00FF_0000_00FF_u64;
    let a = (pairs & mask).wrapping_mul(100 + (1_000_000 << 32));
    let b = ((pairs >> 16) & mask).wrapping_mul(1 + (10_000 << 32));
    Some(a.wrapping_add(b) >> 32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every token the fast path reads gives `str::parse`'s value to the
    /// bit, and every token it refuses is refused or not finite there.
    #[test]
    fn tokens_agree_with_std() {
        let fixed = [
            "0",
            "-0",
            "+0",
            "0.0",
            "-0.0",
            "1",
            "+1",
            "-1",
            "1.",
            ".5",
            "-.5",
            "+.5",
            ".",
            "+",
            "-",
            "",
            "e5",
            "1e",
            "1e+",
            "1e-",
            "1e5",
            "1E-5",
            "1e+22",
            "1e23",
            "1e-22",
            "1e-23",
            "9007199254740992",
            "9007199254740993",
            "9007199254740993e-3",
            "0.1",
            "0.3",
            "123456789012345678",
            "1234567890123456789",
            "12345678901234567890",
            "0.000000000000000000000000001",
            "-0.41412353515625",
            "1.7976931348623157e308",
            "1e309",
            "-1e309",
            "4.9e-324",
            "1e-400",
            "1..2",
            "1.2.3",
            "--1",
            "+-1",
            "1e5.5",
            "1e-0000",
            "1e00001",
            "0e999999",
            "00000000000000000000000001",
            "1-2",
            "1e+-2",
        ];
        for token in fixed {
            check(token);
        }
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let alphabet = b"0123456789012345678901234567890123456789.e+-E";
        for _ in 0..200_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let len = 1 + (state % 26) as usize;
            let mut s = state;
            let token: String = (0..len)
                .map(|_| {
                    s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                    alphabet[((s >> 33) % alphabet.len() as u64) as usize] as char
                })
                .collect();
            check(&token);
        }
    }

    fn check(token: &str) {
        let std = token.parse::<f64>().ok().filter(|v| v.is_finite());
        let fast = finite_number(token.as_bytes());
        assert_eq!(fast.map(f64::to_bits), std.map(f64::to_bits), "{token:?}");
        if let Some((v, end)) = exact_prefix(token.as_bytes(), 0) {
            if end == token.len() {
                assert_eq!(Some(v.to_bits()), std.map(f64::to_bits), "{token:?}");
            }
        }
    }

    /// Random decimals of up to 19 significant digits and exponents in
    /// Clinger's range go through the exact path and match `str::parse`.
    #[test]
    fn exact_path_is_taken_and_exact() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut taken = 0;
        for _ in 0..200_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let digits = 1 + (state % 17) as u32;
            let w = (state >> 8) % 10u64.pow(digits);
            let point = ((state >> 40) % u64::from(digits + 1)) as usize;
            let mut text = format!("{w:0width$}", width = digits as usize);
            text.insert(text.len() - point, '.');
            if state & 1 == 1 {
                text.insert(0, '-');
            }
            if state & 2 == 2 {
                text += &format!("e{}", ((state >> 50) % 15) as i64 - 7);
            }
            if exact_prefix(text.as_bytes(), 0).is_some_and(|(_, end)| end == text.len()) {
                taken += 1;
            }
            check(&text);
        }
        assert!(taken > 150_000, "{taken}");
    }

    #[test]
    fn eight_digits_at_once() {
        let mut state = 0x853c_49e6_748f_ea9b_u64;
        for _ in 0..100_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let text = format!("{:08}", state % 100_000_000);
            assert_eq!(eight_digits(text.as_bytes()), Some(state % 100_000_000));
            let mut bad = text.into_bytes();
            bad[(state >> 40) as usize % 8] =
                [b'/', b':', b'.', b'e', 0x80, 0xfa][(state >> 50) as usize % 6];
            assert_eq!(eight_digits(&bad), None, "{bad:?}");
        }
        assert_eq!(eight_digits(b"99999999"), Some(99_999_999));
        assert_eq!(eight_digits(b"00000000"), Some(0));
    }

    #[test]
    fn plain_lines() {
        let line = NumericLine::new(4, &[2, 0]);
        let mut v = [0.0; 2];
        assert_eq!(line.parse(b" 1.5 ,x y,\t-2e3,z\r\nrest", &mut v), Some(19));
        assert_eq!(v, [-2e3, 1.5]);
        assert_eq!(line.parse(b"1,x,2,z\n", &mut v), Some(8));
        // Not plain, or not whole.
        for text in [
            &b"1,x,2,z"[..],
            b"1,x,2,z\r",
            b"1,x,2,z\rq\n",
            b"1,x,2\n",
            b"1,x,2,z,\n",
            b"1,\"x\",2,z\n",
            b"1,x,nan,z\n",
            b"1,x,inf,z\n",
            b"1,x,,z\n",
            b"1,x,1e999,z\n",
            b"1,\xc3\xa9,2,z\n",
            b"1,x\x01,2,z\n",
            b"1,x,2 3,z\n",
            b"\n",
            b"#1,x,2,z\n",
        ] {
            assert_eq!(line.parse(text, &mut v), None, "{:?}", text);
        }
        let skipped_first = NumericLine::new(2, &[1]);
        let mut w = [0.0; 1];
        assert_eq!(skipped_first.parse(b" # c,1\n", &mut w), None);
        assert_eq!(skipped_first.parse(b" c#,1\n", &mut w), Some(6));
        assert_eq!(w, [1.0]);
    }
}
