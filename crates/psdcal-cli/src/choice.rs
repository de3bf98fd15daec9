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

/// `--lens` of `simulate` and `map`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LensArg {
    #[value(name = "1")]
    One,
    #[value(name = "2")]
    Two,
}

/// `--template` of `simulate`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TemplateArg {
    Scatter14,
    Grid,
}

/// `--method` of `gains`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum GainsMethodArg {
    EqualCurrent,
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

/// `From<$arg> for $lib` mapping the variants of the same names.
macro_rules! same_variants {
    ($arg:ident => $lib:path { $($v:ident),* }) => {
        impl From<$arg> for $lib {
            fn from(a: $arg) -> Self {
                use $lib as Lib;
                match a {
                    $($arg::$v => Lib::$v,)*
                }
            }
        }
    };
}

/// `simulate --raw`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RawArg {
    Csv,
    Npy,
    Tdms,
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

same_variants!(LensArg => psdcal::Lens { One, Two });
same_variants!(TemplateArg => psdcal::TemplateKind { Scatter14, Grid });
same_variants!(GainsMethodArg => psdcal::GainsMethod { EqualCurrent });
same_variants!(RawArg => psdcal::RawFormat { Csv, Npy, Tdms });

/// `export --to`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExportTo {
    /// OpenCV FileStorage YAML (the rational model)
    #[value(name = "opencv")]
    OpenCv,
    /// mrcal .cameramodel (LENSMODEL_OPENCV8)
    Mrcal,
    /// ROS camera_info YAML (plumb_bob or rational_polynomial)
    Ros,
}

same_variants!(ExportTo => psdcal::ExportTarget { OpenCv, Mrcal, Ros });
