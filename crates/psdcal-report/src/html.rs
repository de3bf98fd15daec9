//! Self-contained HTML pages: one file, inline SVG, a small inline style
//! sheet, no script, nothing loaded from the network.
//!
//! Every text given to a [`Block`] is escaped with [`escape_html`]; SVG
//! figures must come from this crate's plot functions (their text is
//! escaped by the SVG backend), and a figure holding a `<script` or a
//! `<foreignObject` is replaced by a note.

use crate::escape::escape_html;

/// The style sheet: responsive tables and figures, printable.
const STYLE: &str = "\
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,'DejaVu Sans',sans-serif;\
margin:0 auto;padding:1rem;max-width:72rem;color:#1a1a1a;background:#fff;line-height:1.45}\
h1{font-size:1.6rem}h2{font-size:1.3rem;margin-top:2rem;border-bottom:1px solid #ccc}\
.table-wrap{max-width:100%;overflow-x:auto;margin:0.5rem 0 1rem}\
table{border-collapse:collapse;font-size:0.9rem;font-variant-numeric:tabular-nums}\
caption{text-align:left;font-weight:600;padding:0.3rem 0;position:sticky;left:0;\
max-width:calc(100vw - 2rem)}\
th,td{border:1px solid #ccc;padding:0.25rem 0.5rem;text-align:right;white-space:nowrap}\
th:first-child,td:first-child{text-align:left}thead th{background:#f2f2f2;white-space:normal}\
.correlation td{text-align:center;min-width:3.2em}\
figure{margin:1rem 0;max-width:100%}figure svg{max-width:100%;height:auto;display:block}\
figcaption{font-size:0.9rem;color:#444}li,p{overflow-wrap:anywhere}\
.figures{display:flex;flex-wrap:wrap;gap:1rem}.figures figure{flex:1 1 20rem;margin:0}\
@media print{body{max-width:none;padding:0}.table-wrap{overflow:visible}\
figure,table{break-inside:avoid}h2{break-after:avoid}}";

/// A table of text cells (escaped when rendered).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// Caption above the table.
    pub caption: String,
    /// Column headings.
    pub headers: Vec<String>,
    /// Rows of cells.
    pub rows: Vec<Vec<String>>,
}

/// A part of a page.
#[derive(Debug, Clone, PartialEq)]
pub enum Block {
    /// A section heading.
    Heading(String),
    /// A paragraph.
    Paragraph(String),
    /// A bulleted list.
    List(Vec<String>),
    /// A table.
    Table(Table),
    /// Figures side by side (wrapping on narrow screens): `(svg, caption)`.
    Figures(Vec<(String, String)>),
    /// A table whose cells are coloured by a shade in [−1, 1] with
    /// [`correlation_colour`] (blue −1, white 0, red +1); `None` and cells
    /// beyond `shades` stay white.
    Shaded {
        /// The table.
        table: Table,
        /// Per row, per cell: the shade.
        shades: Vec<Vec<Option<f64>>>,
    },
    /// A correlation matrix as a table whose cells are coloured by the
    /// value (blue −1, white 0, red +1), two decimals in each.
    Correlation {
        /// Caption above the table.
        caption: String,
        /// Row and column names.
        names: Vec<String>,
        /// The square matrix, one row per name.
        values: Vec<Vec<f64>>,
    },
}

/// The background of a correlation `r` (clamped to [−1, 1]): white at 0,
/// towards blue (−1) or red (+1); and a text colour that stays readable.
pub fn correlation_colour(r: f64) -> (String, &'static str) {
    let r = if r.is_finite() {
        r.clamp(-1.0, 1.0)
    } else {
        0.0
    };
    let (end, a) = if r < 0.0 {
        ((33.0, 102.0, 172.0), -r)
    } else {
        ((178.0, 24.0, 43.0), r)
    };
    let mix = |c: f64| (255.0 + a * (c - 255.0)).round() as u8;
    let background = format!("#{:02x}{:02x}{:02x}", mix(end.0), mix(end.1), mix(end.2));
    (background, if a > 0.6 { "#fff" } else { "#111" })
}

/// An HTML page.
#[derive(Debug, Clone, PartialEq)]
pub struct Page {
    /// Title (also the top heading).
    pub title: String,
    /// Its blocks, in order.
    pub blocks: Vec<Block>,
}

impl Page {
    /// An empty page.
    pub fn new(title: &str) -> Self {
        Self {
            title: title.to_string(),
            blocks: Vec::new(),
        }
    }

    /// Appends a block.
    pub fn push(&mut self, block: Block) -> &mut Self {
        self.blocks.push(block);
        self
    }

    /// The page as one HTML document.
    pub fn render(&self) -> String {
        let mut out = String::new();
        out.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        out.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
        out.push_str(
            "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; \
             style-src 'unsafe-inline'; img-src data:\">\n",
        );
        out.push_str(&format!("<title>{}</title>\n", escape_html(&self.title)));
        out.push_str(&format!("<style>{STYLE}</style>\n</head>\n<body>\n"));
        out.push_str(&format!("<h1>{}</h1>\n", escape_html(&self.title)));
        for block in &self.blocks {
            render_block(&mut out, block);
        }
        out.push_str("</body>\n</html>\n");
        out
    }
}

fn render_block(out: &mut String, block: &Block) {
    match block {
        Block::Heading(text) => out.push_str(&format!("<h2>{}</h2>\n", escape_html(text))),
        Block::Paragraph(text) => out.push_str(&format!("<p>{}</p>\n", escape_html(text))),
        Block::List(items) => {
            out.push_str("<ul>\n");
            for item in items {
                out.push_str(&format!("<li>{}</li>\n", escape_html(item)));
            }
            out.push_str("</ul>\n");
        }
        Block::Table(table) => render_table(out, table, &[]),
        Block::Shaded { table, shades } => render_table(out, table, shades),
        Block::Correlation {
            caption,
            names,
            values,
        } => render_correlation(out, caption, names, values),
        Block::Figures(figures) => {
            out.push_str("<div class=\"figures\">\n");
            for (svg, caption) in figures {
                out.push_str("<figure>\n");
                out.push_str(&inline_svg(svg));
                out.push_str(&format!(
                    "<figcaption>{}</figcaption>\n</figure>\n",
                    escape_html(caption)
                ));
            }
            out.push_str("</div>\n");
        }
    }
}

/// A table; a cell with a shade gets its background and text colour.
/// Without headers there is no header row.
fn render_table(out: &mut String, table: &Table, shades: &[Vec<Option<f64>>]) {
    out.push_str("<div class=\"table-wrap\"><table>\n");
    if !table.caption.is_empty() {
        out.push_str(&format!(
            "<caption>{}</caption>\n",
            escape_html(&table.caption)
        ));
    }
    if !table.headers.is_empty() {
        out.push_str("<thead><tr>");
        for h in &table.headers {
            out.push_str(&format!("<th scope=\"col\">{}</th>", escape_html(h)));
        }
        out.push_str("</tr></thead>\n");
    }
    out.push_str("<tbody>\n");
    for (r, row) in table.rows.iter().enumerate() {
        out.push_str("<tr>");
        for (c, cell) in row.iter().enumerate() {
            match shades.get(r).and_then(|s| s.get(c)).copied().flatten() {
                Some(shade) => {
                    let (bg, fg) = correlation_colour(shade);
                    out.push_str(&format!(
                        "<td style=\"background:{bg};color:{fg}\">{}</td>",
                        escape_html(cell)
                    ));
                }
                None => out.push_str(&format!("<td>{}</td>", escape_html(cell))),
            }
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</tbody></table></div>\n");
}

fn render_correlation(out: &mut String, caption: &str, names: &[String], values: &[Vec<f64>]) {
    out.push_str("<div class=\"table-wrap\"><table class=\"correlation\">\n");
    out.push_str(&format!("<caption>{}</caption>\n", escape_html(caption)));
    out.push_str("<thead><tr><th scope=\"col\"></th>");
    for n in names {
        out.push_str(&format!("<th scope=\"col\">{}</th>", escape_html(n)));
    }
    out.push_str("</tr></thead>\n<tbody>\n");
    for (name, row) in names.iter().zip(values) {
        out.push_str(&format!("<tr><th scope=\"row\">{}</th>", escape_html(name)));
        for &r in row {
            let (bg, fg) = correlation_colour(r);
            let text = if r.is_finite() {
                format!("{r:.2}")
            } else {
                "–".into()
            };
            out.push_str(&format!(
                "<td style=\"background:{bg};color:{fg}\">{text}</td>"
            ));
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</tbody></table></div>\n");
}

/// An SVG document ready to inline: the XML declaration dropped; a figure
/// that holds a script or foreign content becomes an escaped note.
pub fn inline_svg(svg: &str) -> String {
    let lower = svg.to_ascii_lowercase();
    if lower.contains("<script") || lower.contains("<foreignobject") || lower.contains("<!entity") {
        return "<p>(figure left out: it held active content)</p>\n".to_string();
    }
    let mut body = svg.trim_start();
    if body.starts_with("<?xml") {
        body = body
            .find("?>")
            .map_or("", |end| &body[end + 2..])
            .trim_start();
    }
    format!("{}\n", body.trim_end())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn user_text_is_escaped_everywhere() {
        let evil = "<script>alert('x')</script>&\"";
        let mut page = Page::new(evil);
        page.push(Block::Heading(evil.into()))
            .push(Block::Paragraph(evil.into()))
            .push(Block::List(vec![evil.into()]))
            .push(Block::Table(Table {
                caption: evil.into(),
                headers: vec![evil.into()],
                rows: vec![vec![evil.into()]],
            }))
            .push(Block::Figures(vec![("<svg></svg>".into(), evil.into())]));
        let html = page.render();
        assert!(!html.contains("<script"));
        assert!(!html.contains("alert('x')"));
        assert_eq!(html.matches("&lt;script&gt;alert(&#39;x&#39;)").count(), 9);
        let mut page = Page::new("m");
        page.push(Block::Correlation {
            caption: evil.into(),
            names: vec![evil.into()],
            values: vec![vec![0.5]],
        });
        let html = page.render();
        assert!(!html.contains("<script"));
        assert_eq!(html.matches("&lt;script&gt;").count(), 3);
    }

    #[test]
    fn correlations_are_coloured_by_value() {
        assert_eq!(correlation_colour(0.0), ("#ffffff".to_string(), "#111"));
        assert_eq!(correlation_colour(1.0), ("#b2182b".to_string(), "#fff"));
        assert_eq!(correlation_colour(-1.0), ("#2166ac".to_string(), "#fff"));
        assert_eq!(correlation_colour(f64::NAN).0, "#ffffff");
        let mut page = Page::new("m");
        page.push(Block::Correlation {
            caption: "c".into(),
            names: vec!["f".into(), "k1".into()],
            values: vec![vec![1.0, -0.93], vec![-0.93, 1.0]],
        });
        let html = page.render();
        assert!(html.contains("<td style=\"background:#b2182b;color:#fff\">1.00</td>"));
        assert!(html.contains(">-0.93</td>"));
        let mut page = Page::new("s");
        page.push(Block::Shaded {
            table: Table {
                caption: String::new(),
                headers: Vec::new(),
                rows: vec![vec!["a".into(), "<b>".into(), "c".into()]],
            },
            shades: vec![vec![None, Some(-1.0)]],
        });
        let html = page.render();
        assert!(!html.contains("<thead>"));
        assert!(html.contains("<tr><td>a</td><td style=\"background:#2166ac;color:#fff\">&lt;b&gt;</td><td>c</td></tr>"));
    }

    #[test]
    fn svg_is_inlined_without_declaration_and_scripts_are_refused() {
        assert_eq!(
            inline_svg("<?xml version=\"1.0\"?>\n<svg a=\"1\"></svg>"),
            "<svg a=\"1\"></svg>\n"
        );
        assert!(!inline_svg("<svg><script>x</script></svg>").contains("<script"));
        assert!(!inline_svg("<svg><foreignObject/></svg>").contains("foreignObject"));
    }

    #[test]
    fn page_loads_nothing_and_runs_nothing() {
        let html = Page::new("t").render();
        assert!(html.contains("Content-Security-Policy"));
        assert!(html.contains("@media print"));
        assert!(html.contains("max-width:100%"));
        for bad in [
            "<script", "<link", "<img", "http://", "https://", "@import", "url(",
        ] {
            assert!(!html.contains(bad), "{bad}");
        }
    }
}
