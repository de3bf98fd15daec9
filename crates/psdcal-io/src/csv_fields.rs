//! One CSV line into its fields (the quoting rules of psdcal's CSV files):
//! commas separate fields; a field may be enclosed in `"` (then it may hold
//! commas, and `""` stands for one quote); blanks around a quoted field are
//! dropped, blanks in an unquoted field are kept (the reader trims values
//! where it needs to). A quoted field cannot span lines: an unclosed quote is
//! an error, reported with the line by the caller.

use crate::error::quoted;

/// Splits one line into fields: commas separate, `"` quotes (with `""` for a
/// literal quote), whitespace around a quoted field is dropped.
pub(crate) fn split_fields(line: &str) -> Result<Vec<String>, String> {
    enum State {
        /// At the start of a field; holds the whitespace seen so far.
        Start,
        Unquoted,
        Quoted,
        AfterQuote,
    }
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut state = State::Start;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match state {
            State::Start => match c {
                ',' => fields.push(std::mem::take(&mut field)),
                '"' => {
                    field.clear();
                    state = State::Quoted;
                }
                c if c.is_whitespace() => field.push(c),
                c => {
                    field.push(c);
                    state = State::Unquoted;
                }
            },
            State::Unquoted => {
                if c == ',' {
                    fields.push(std::mem::take(&mut field));
                    state = State::Start;
                } else {
                    field.push(c);
                }
            }
            State::Quoted => {
                if c == '"' {
                    if chars.peek() == Some(&'"') {
                        chars.next();
                        field.push('"');
                    } else {
                        state = State::AfterQuote;
                    }
                } else {
                    field.push(c);
                }
            }
            State::AfterQuote => match c {
                ',' => {
                    fields.push(std::mem::take(&mut field));
                    state = State::Start;
                }
                c if c.is_whitespace() => {}
                c => {
                    return Err(format!(
                        "unexpected character {} after the closing quote of field {}; \
                         expected a comma",
                        quoted(&c.to_string()),
                        fields.len() + 1
                    ))
                }
            },
        }
    }
    if let State::Quoted = state {
        return Err(format!(
            "field {} opens a quote that is not closed on this line; expected a closing '\"' \
             (quoted fields cannot span lines)",
            fields.len() + 1
        ));
    }
    fields.push(field);
    Ok(fields)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoted_fields() {
        assert_eq!(
            split_fields(r#"1, "a,b" ,"say ""hi""",x y"#).unwrap(),
            vec!["1", "a,b", "say \"hi\"", "x y"]
        );
        assert_eq!(split_fields("").unwrap(), vec![""]);
        assert_eq!(split_fields("a,").unwrap(), vec!["a", ""]);
        let e = split_fields(r#"1,"open"#).unwrap_err();
        assert!(e.contains("field 2 opens a quote"), "{e}");
        let e = split_fields(r#""a"b"#).unwrap_err();
        assert!(e.contains("after the closing quote of field 1"), "{e}");
    }
}
