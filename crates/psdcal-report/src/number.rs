//! Numbers as people read them: the study pages' four significant digits,
//! and an estimate with its standard deviation, rounded by the σ.
//!
//! `value_with_sigma`: σ to two significant digits, the value to the same
//! decimal place (`7.958 ± 0.024 mm`); beyond 1e-2…1e5 a shared power of
//! ten (`(9.945 ± 0.049) × 10⁻³ mm⁻²`). Without a σ (or a σ of zero), five
//! significant digits ([`value_with_digits`] for any other count). Units
//! written `mm^-2` print as `mm⁻²`.

/// A number with four significant digits, in plain or scientific notation
/// (the same form as the study's Markdown tables).
pub fn num(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if (1e-2..1e4).contains(&x.abs()) {
        let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
        format!("{x:.digits$}")
    } else {
        format!("{x:.3e}")
    }
}

/// A number that rounded to zero printed without its sign (`-0.0` → `0.0`).
fn unsigned_zero(text: String) -> String {
    match text.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => text,
    }
}

fn superscript(n: i32) -> String {
    let digits = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::new();
    if n < 0 {
        s.push('⁻');
    }
    for c in n.unsigned_abs().to_string().chars() {
        s.push(digits[c.to_digit(10).unwrap_or(0) as usize]);
    }
    s
}

/// A unit as printed: `mm^-2` → `mm⁻²`.
pub fn unit_text(unit: &str) -> String {
    match unit.split_once('^') {
        Some((base, exp)) => match exp.parse::<i32>() {
            Ok(n) => format!("{base}{}", superscript(n)),
            Err(_) => unit.to_string(),
        },
        None => unit.to_string(),
    }
}

/// `value ± sigma unit`, rounded by σ (module documentation).
pub fn value_with_sigma(value: f64, sigma: Option<f64>, unit: &str) -> String {
    format_value(value, sigma, 5, unit)
}

/// `value unit` with `digits` significant digits (at least one), in the
/// same plain or shared-power-of-ten form as [`value_with_sigma`]:
/// `value_with_digits(0.34491, 2, "deg")` is `0.34 deg`.
pub fn value_with_digits(value: f64, digits: usize, unit: &str) -> String {
    format_value(value, None, digits.max(1), unit)
}

/// The one formatter behind [`value_with_sigma`] and [`value_with_digits`]:
/// rounded by σ when σ is positive, else to `digits` significant digits.
fn format_value(value: f64, sigma: Option<f64>, digits: usize, unit: &str) -> String {
    let unit = unit_text(unit);
    let space = if unit.is_empty() { "" } else { " " };
    if !value.is_finite() {
        return "–".into();
    }
    let magnitude = value.abs().max(sigma.unwrap_or(0.0).abs());
    let exponent = if magnitude != 0.0 && !(1e-2..1e5).contains(&magnitude) {
        magnitude.log10().floor() as i32
    } else {
        0
    };
    let scale = 10f64.powi(exponent);
    let (v, s) = (value / scale, sigma.map(|s| s / scale));
    let body = match s.filter(|s| s.is_finite() && *s > 0.0) {
        Some(s) => {
            // σ to two significant digits; the value to the same place.
            let decimals = (1 - s.log10().floor() as i32).clamp(0, 15) as usize;
            format!(
                "{} ± {s:.decimals$}",
                unsigned_zero(format!("{v:.decimals$}"))
            )
        }
        None => {
            let decimals = if v == 0.0 {
                0
            } else {
                (digits as i32 - 1 - v.abs().log10().floor() as i32).clamp(0, 15) as usize
            };
            unsigned_zero(format!("{v:.decimals$}"))
        }
    };
    match (exponent, sigma.is_some_and(|s| s > 0.0)) {
        (0, _) => format!("{body}{space}{unit}"),
        (e, true) => format!("({body}) × 10{}{space}{unit}", superscript(e)),
        (e, false) => format!("{body} × 10{}{space}{unit}", superscript(e)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounded_by_sigma_with_units() {
        assert_eq!(
            value_with_sigma(7.958429, Some(0.024164), "mm"),
            "7.958 ± 0.024 mm"
        );
        assert_eq!(
            value_with_sigma(9.94455e-3, Some(4.9347e-5), "mm^-2"),
            "(9.945 ± 0.049) × 10⁻³ mm⁻²"
        );
        assert_eq!(
            value_with_sigma(3.13667e-5, Some(1.7592e-6), "mm^-4"),
            "(3.14 ± 0.18) × 10⁻⁵ mm⁻⁴"
        );
        assert_eq!(
            value_with_sigma(0.505391, Some(0.0066586), "mm"),
            "0.5054 ± 0.0067 mm"
        );
        assert_eq!(value_with_sigma(1234.5, Some(25.0), "mm"), "1234 ± 25 mm");
        assert_eq!(value_with_sigma(0.0, None, "mm"), "0 mm");
        assert_eq!(value_with_sigma(8.0, None, "mm"), "8.0000 mm");
        assert_eq!(
            value_with_sigma(-1.3058e-3, None, "mm^-2"),
            "-1.3058 × 10⁻³ mm⁻²"
        );
        assert_eq!(value_with_sigma(f64::NAN, None, "mm"), "–");
        assert_eq!(unit_text("mm^-6"), "mm⁻⁶");
        assert_eq!(value_with_digits(0.344913, 2, "deg"), "0.34 deg");
        assert_eq!(value_with_digits(3373.4, 3, "mm"), "3373 mm");
        assert_eq!(value_with_digits(3.0864e-5, 2, "mm^-2"), "3.1 × 10⁻⁵ mm⁻²");
        assert_eq!(value_with_digits(-0.084, 2, ""), "-0.084");
        assert_eq!(
            value_with_sigma(-2e-8, Some(2.3e-6), ""),
            "(0.0 ± 2.3) × 10⁻⁶"
        );
    }
}
