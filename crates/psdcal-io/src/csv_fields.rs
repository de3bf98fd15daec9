//! One CSV line into its fields (the quoting rules of psdcal's CSV files):
//! commas separate fields; a field may be enclosed in `"` (then it may hold
//! commas, and `""` stands for one quote); blanks around a quoted field are
//! dropped, blanks in an unquoted field are kept (the reader trims values
//! where it needs to). A quoted field cannot span lines: an unclosed quote is
//! an error, reported with the line by the caller.

use crate::error::quoted;

/// Splits one line into fields: commas separate, `"` quotes (with `""` for a
/// literal quote), whitespace around a quoted field is dropped. A line
/// without quotes (nearly every line of a data file) is split at its commas
/// directly, which is what the rules give for it.
pub(crate) fn split_fields(line: &str) -> Result<Vec<String>, String> {
    if line.contains('"') {
        split_quoted(line)
    } else {
        Ok(line.split(',').map(str::to_owned).collect())
    }
}

/// [`split_fields`] by the quoting rules, character by character.
fn split_quoted(line: &str) -> Result<Vec<String>, String> {
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

    /// The direct split of a quote-free line is what the quoting rules give.
    #[test]
    fn quote_free_lines_split_as_the_rules_do() {
        let alphabet = [',', ' ', '\t', 'a', '1', '.', '-', 'é', '#'];
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        for _ in 0..2000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let len = (state % 24) as usize;
            let line: String = (0..len)
                .map(|k| alphabet[((state >> (2 * k % 60)) % alphabet.len() as u64) as usize])
                .collect();
            assert_eq!(split_fields(&line), split_quoted(&line), "{line:?}");
        }
    }

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
