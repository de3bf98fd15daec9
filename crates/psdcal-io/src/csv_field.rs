//! The one CSV field writer of psdcal's outputs: a field is quoted (RFC 4180,
//! `"` doubled) when it holds a separator, a quote or a line break, a `;`
//! (the template's list separator), or starts with `#` (a comment to
//! psdcal's readers); any other field is written as it is.

/// `s` as one CSV field.
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r', ';']) || s.starts_with('#') {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::csv_field;

    #[test]
    fn quotes_only_what_a_reader_would_misread() {
        assert_eq!(csv_field("led7"), "led7");
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(csv_field("#1"), "\"#1\"");
        assert_eq!(csv_field("h;v"), "\"h;v\"");
        assert_eq!(csv_field("two\nlines"), "\"two\nlines\"");
    }
}
