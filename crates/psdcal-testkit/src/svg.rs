//! Reading back what a report drew: the `<polyline>`s of an SVG (plotters
//! writes one per line or arrow), for tests that map drawn lengths back to
//! data units.

/// The `points` of every `<polyline>` of `svg`, in pixels, each with its
/// whole tag (for its stroke colour).
///
/// # Panics
///
/// On a `<polyline` without `/>`, `points="…"` or numeric `x,y` pairs: a
/// test helper, for SVGs psdcal wrote.
pub fn polylines(svg: &str) -> Vec<(String, Vec<(f64, f64)>)> {
    svg.split("<polyline")
        .skip(1)
        .map(|rest| {
            let tag = &rest[..rest.find("/>").expect("a closed <polyline>")];
            let start = tag.find("points=\"").expect("points=") + 8;
            let text = &tag[start..start + tag[start..].find('"').expect("closing quote")];
            let points = text
                .split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').expect("an x,y pair");
                    (x.parse().expect("numeric x"), y.parse().expect("numeric y"))
                })
                .collect();
            (tag.to_string(), points)
        })
        .collect()
}
