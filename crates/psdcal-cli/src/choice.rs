//! Options with a fixed set of values: clap `ValueEnum`s, mapped onto the
//! library's enums, and a parser whose refusal says what was expected.

use clap::ValueEnum;

/// Parses a `ValueEnum`; the refusal lists the accepted values.
pub fn choice<T: ValueEnum>(text: &str) -> Result<T, String> {
    T::from_str(text.trim(), true).map_err(|_| {
        let names: Vec<String> = T::value_variants()
            .iter()
            .filter_map(|v| v.to_possible_value())
            .map(|p| p.get_name().to_string())
            .collect();
        format!(
            "unknown value '{text}'; expected one of {}",
            names.join(", ")
        )
    })
}

/// The name of a `ValueEnum` value.
pub fn name<T: ValueEnum>(value: &T) -> String {
    value
        .to_possible_value()
        .map_or_else(String::new, |p| p.get_name().to_string())
}
