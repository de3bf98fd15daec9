//! Numbers as psdcal writes them in files and messages: the shortest text
//! that reads back to the same `f64`, in plain decimals for ordinary
//! magnitudes and in scientific notation beyond them (so `1e308` is never
//! a 309-digit number). A non-finite value is written as empty text.

/// Below this magnitude (and above zero) numbers are written in scientific
/// notation.
const SMALLEST_PLAIN: f64 = 1e-7;
/// From this magnitude on numbers are written in scientific notation.
const LARGEST_PLAIN: f64 = 1e16;

/// The shortest round-trip text of `v` (`0.5`, `-1.3058e-3` as `-0.0013058`,
/// `1e300`); empty for NaN and infinities.
pub fn number_text(v: f64) -> String {
    if !v.is_finite() {
        return String::new();
    }
    let magnitude = v.abs();
    if v != 0.0 && !(SMALLEST_PLAIN..LARGEST_PLAIN).contains(&magnitude) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}

/// A number shown in a message: [`number_text`], or `NaN` / `inf` spelled
/// out.
pub fn shown_number(v: f64) -> String {
    if v.is_finite() {
        number_text(v)
    } else {
        v.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_then_scientific() {
        assert_eq!(number_text(0.5), "0.5");
        assert_eq!(number_text(-2.0), "-2");
        assert_eq!(number_text(1e-7), "0.0000001");
        assert_eq!(number_text(1.5e-8), "1.5e-8");
        assert_eq!(number_text(1e308), "1e308");
        assert_eq!(number_text(-1.25e16), "-1.25e16");
        assert_eq!(number_text(0.0), "0");
        assert_eq!(number_text(f64::NAN), "");
        assert_eq!(shown_number(f64::INFINITY), "inf");
        for v in [1e308, 1.234_567_890_123_4e-300, 123.456, f64::MIN_POSITIVE] {
            assert_eq!(number_text(v).parse::<f64>().unwrap(), v);
        }
    }
}
