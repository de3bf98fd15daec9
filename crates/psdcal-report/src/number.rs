//! Numbers as the study pages and colour bars show them.

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
