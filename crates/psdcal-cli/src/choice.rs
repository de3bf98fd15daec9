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

/// The tables of `study`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TableArg {
    Table1,
    Table2,
    Table3,
    Table4,
    Table5,
    Table6,
    Table7,
    Table8,
    Table9,
    Table10,
    Fig9,
    /// The PSD map's condition (run only when named).
    Psdmap,
    All,
}

/// `simulate --impairments` (`none`: a clean card).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ImpairmentArg {
    Dc,
    Hum,
    Drift,
    Quantise,
    Clock,
    Transients,
    None,
}

/// The card of `--impairments`.
pub fn impairments(list: &[ImpairmentArg]) -> psdcal::Impairments {
    use psdcal::Impairment as I;
    let kinds: Vec<I> = list
        .iter()
        .filter_map(|a| match a {
            ImpairmentArg::Dc => Some(I::Dc),
            ImpairmentArg::Hum => Some(I::Hum),
            ImpairmentArg::Drift => Some(I::Drift),
            ImpairmentArg::Quantise => Some(I::Quantise),
            ImpairmentArg::Clock => Some(I::Clock),
            ImpairmentArg::Transients => Some(I::Transients),
            ImpairmentArg::None => None,
        })
        .collect();
    psdcal::Impairments::only(&kinds)
}
