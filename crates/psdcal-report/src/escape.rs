//! Escaping of user-supplied text for HTML.

/// `text` with `& < > " '` replaced by entities: safe in HTML text and in
/// quoted attribute values.
///
/// ```
/// assert_eq!(
///     psdcal_report::escape_html(r#"<a href="x">'LED' & co</a>"#),
///     "&lt;a href=&quot;x&quot;&gt;&#39;LED&#39; &amp; co&lt;/a&gt;"
/// );
/// ```
pub fn escape_html(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            other => out.push(other),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::escape_html;

    #[test]
    fn every_special_character_is_escaped() {
        assert_eq!(escape_html("&<>\"'"), "&amp;&lt;&gt;&quot;&#39;");
        assert_eq!(escape_html("LED 1 – ok"), "LED 1 – ok");
        assert_eq!(
            escape_html("<script>alert(1)</script>"),
            "&lt;script&gt;alert(1)&lt;/script&gt;"
        );
        assert_eq!(escape_html(""), "");
    }
}
