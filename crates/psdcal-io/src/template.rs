//! template.csv: the calibration template, one row per LED (docs/formats.md).
//!
//! | column | meaning |
//! | --- | --- |
//! | `led` | LED identifier (text; an integer is just text), unique |
//! | `X_mm`, `Y_mm` | LED position on the template plane, mm |
//! | `lines` (optional) | `;`-separated labels of the collinear groups the LED belongs to, e.g. `r1;c3` |
//! | `Z_mm` (optional) | the third coordinate of LEDs or emitters surveyed in 3-D (a non-coplanar template, e.g. IR emitters fixed in a room, in the room's frame), mm |
//!
//! Without `Z_mm` every LED has `z_mm = None` and the template is planar
//! (`Z = 0`); with it every row needs a finite number.
//!
//! Reading enforces: a unique, non-empty `led`; finite coordinates; at least
//! [`Template::MIN_LEDS`] LEDs. A line group with fewer than
//! [`Template::MIN_LINE_LEDS`] LEDs cannot constrain straightness and is
//! reported by [`Template::warnings`].

use std::collections::HashMap;

use crate::csv_table::CsvTable;
use crate::error::IoError;
use crate::limits::ReadLimits;
use crate::location::Location;
use crate::warning::Warning;

const EXPECTED_COLUMNS: &str = "led, X_mm, Y_mm (and optionally lines)";

/// One LED of the template.
#[derive(Debug, Clone, PartialEq)]
pub struct Led {
    /// Identifier, as written (trimmed).
    pub id: String,
    /// Position on the template plane, mm.
    pub x_mm: f64,
    /// Position on the template plane, mm.
    pub y_mm: f64,
    /// Third coordinate of a surveyed (non-coplanar) template, mm; `None`
    /// when the file has no `Z_mm` column.
    pub z_mm: Option<f64>,
    /// Labels of the collinear groups the LED belongs to, in file order,
    /// without repeats.
    pub lines: Vec<String>,
    /// Physical line of its row, 1-based.
    pub line_no: usize,
}

/// A collinear group of LEDs declared by the `lines` column.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LineGroup {
    /// The label.
    pub name: String,
    /// Indices into [`Template::leds`], in file order.
    pub leds: Vec<usize>,
}

/// A calibration template.
#[derive(Debug, Clone, PartialEq)]
pub struct Template {
    /// File name, for messages.
    pub source: String,
    /// The LEDs, in file order.
    pub leds: Vec<Led>,
}

impl Template {
    /// Fewest LEDs a template may have (a homography needs four points).
    pub const MIN_LEDS: usize = 4;
    /// Fewest LEDs a line group needs to constrain straightness.
    pub const MIN_LINE_LEDS: usize = 3;
    csv_table_readers!("template.csv");

    fn from_table(table: CsvTable) -> Result<Self, IoError> {
        let led_col = table.column("led")?;
        let x_col = table.column("X_mm")?;
        let y_col = table.column("Y_mm")?;
        let lines_col = table.find_column("lines")?;
        let z_col = table.find_column("Z_mm")?;
        table.require_rows()?;
        let mut leds: Vec<Led> = Vec::with_capacity(table.rows.len());
        let mut first_line: HashMap<String, usize> = HashMap::new();
        for row in &table.rows {
            let id = table.identifier(row, &led_col, "an LED identifier")?;
            let x_mm = table.number(row, &x_col)?;
            let y_mm = table.number(row, &y_col)?;
            let z_mm = z_col.as_ref().map(|c| table.number(row, c)).transpose()?;
            let mut lines: Vec<String> = Vec::new();
            if let Some(col) = &lines_col {
                for label in table.text(row, col).split(';').map(str::trim) {
                    if !label.is_empty() && !lines.iter().any(|l| l == label) {
                        lines.push(label.to_string());
                    }
                }
            }
            if let Some(&first) = first_line.get(&id) {
                return Err(IoError::Duplicate {
                    at: table.at(row.line),
                    first_line: first,
                    what: format!("LED '{id}'"),
                });
            }
            first_line.insert(id.clone(), row.line);
            leds.push(Led {
                id,
                x_mm,
                y_mm,
                z_mm,
                lines,
                line_no: row.line,
            });
        }
        if leds.len() < Self::MIN_LEDS {
            return Err(IoError::Invalid {
                at: Location::file(&table.source),
                message: format!(
                    "the template has {} LED{}; expected at least {}",
                    leds.len(),
                    if leds.len() == 1 { "" } else { "s" },
                    Self::MIN_LEDS
                ),
            });
        }
        Ok(Self {
            source: table.source,
            leds,
        })
    }

    /// Whether the template has a `Z_mm` column with a non-zero value (a
    /// non-coplanar template, for the 3-D calibration).
    pub fn is_three_d(&self) -> bool {
        self.leds.iter().any(|l| l.z_mm.is_some_and(|z| z != 0.0))
    }

    /// The index of the LED with identifier `id`.
    pub fn index_of(&self, id: &str) -> Option<usize> {
        self.leds.iter().position(|led| led.id == id)
    }

    /// The declared line groups, in order of first appearance.
    pub fn line_groups(&self) -> Vec<LineGroup> {
        let mut groups: Vec<LineGroup> = Vec::new();
        for (index, led) in self.leds.iter().enumerate() {
            for name in &led.lines {
                match groups.iter_mut().find(|g| &g.name == name) {
                    Some(group) => group.leds.push(index),
                    None => groups.push(LineGroup {
                        name: name.clone(),
                        leds: vec![index],
                    }),
                }
            }
        }
        groups
    }

    /// Warnings about the template: line groups too short to be used.
    pub fn warnings(&self) -> Vec<Warning> {
        self.line_groups()
            .into_iter()
            .filter(|g| g.leds.len() < Self::MIN_LINE_LEDS)
            .map(|g| Warning::ShortLineGroup {
                file: self.source.clone(),
                lines: g
                    .leds
                    .iter()
                    .filter_map(|&i| self.leds.get(i).map(|led| led.line_no))
                    .collect(),
                group: g.name,
                min: Self::MIN_LINE_LEDS,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const VALID: &str = "\
# A 2 x 3 grid
led,X_mm,Y_mm,lines
1,0,0,r1;c1
2,10,0,r1
3,20,0,r1

4,0,10,c1
5,10,10,
6,20,10,
";

    #[test]
    fn reads_a_valid_template() {
        let t = Template::from_str("template.csv", VALID).unwrap();
        assert_eq!(t.source, "template.csv");
        assert_eq!(t.leds.len(), 6);
        assert_eq!(
            t.leds[0],
            Led {
                id: "1".into(),
                x_mm: 0.0,
                y_mm: 0.0,
                z_mm: None,
                lines: vec!["r1".into(), "c1".into()],
                line_no: 3,
            }
        );
        assert_eq!(t.leds[3].line_no, 7);
        assert_eq!(t.leds[5].line_no, 9);
        assert_eq!((t.leds[5].x_mm, t.leds[5].y_mm), (20.0, 10.0));
        assert!(t.leds[4].lines.is_empty());
        assert_eq!(t.index_of("5"), Some(4));
        assert_eq!(t.index_of("05"), None);
        assert_eq!(
            t.line_groups(),
            vec![
                LineGroup {
                    name: "r1".into(),
                    leds: vec![0, 1, 2]
                },
                LineGroup {
                    name: "c1".into(),
                    leds: vec![0, 3]
                },
            ]
        );
    }

    #[test]
    fn reordered_extra_columns_crlf_bom() {
        let text =
            "\u{feff}note,Y_mm,led,X_mm\r\na,1.5,A,-2\r\nb,2,B,3e1\r\nc,0,C,0\r\nd,0,D,1\r\n";
        let t = Template::from_str("t.csv", text).unwrap();
        let ids: Vec<&str> = t.leds.iter().map(|l| l.id.as_str()).collect();
        assert_eq!(ids, ["A", "B", "C", "D"]);
        assert_eq!((t.leds[0].x_mm, t.leds[0].y_mm), (-2.0, 1.5));
        assert_eq!((t.leds[1].x_mm, t.leds[1].y_mm), (30.0, 2.0));
        assert_eq!(t.leds[3].line_no, 5);
        assert!(t.line_groups().is_empty());
    }

    #[test]
    fn lowercase_coordinate_names_are_accepted() {
        let text = "led,x_mm,y_mm\n1,0,0\n2,1,0\n3,0,1\n4,1,1\n";
        let t = Template::from_str("t.csv", text).unwrap();
        assert_eq!((t.leds[3].x_mm, t.leds[3].y_mm), (1.0, 1.0));
    }

    #[test]
    fn short_line_group_warns_with_its_lines() {
        let t = Template::from_str("template.csv", VALID).unwrap();
        let w = t.warnings();
        assert_eq!(
            w,
            vec![Warning::ShortLineGroup {
                file: "template.csv".into(),
                group: "c1".into(),
                lines: vec![3, 7],
                min: 3,
            }]
        );
        assert_eq!(w[0].line(), Some(3));
        assert_eq!(
            w[0].to_string(),
            "template.csv:3: line group 'c1' has 2 LEDs (lines 3, 7); expected at least 3: it \
             cannot constrain straightness"
        );
    }

    #[test]
    fn duplicate_led_names_both_lines() {
        let text = "led,X_mm,Y_mm\n1,0,0\n2,1,0\n# c\n3,0,1\n2,1,1\n";
        let e = Template::from_str("template.csv", text).unwrap_err();
        assert_eq!(
            e.to_string(),
            "template.csv:6: LED '2' appears twice (first on line 3)"
        );
        assert_eq!(e.line(), Some(6));
    }

    #[test]
    fn z_column_makes_a_surveyed_template() {
        let planar = Template::from_str("t.csv", VALID).unwrap();
        assert!(planar.leds.iter().all(|l| l.z_mm.is_none()));
        assert!(!planar.is_three_d());
        let text = "led,X_mm,Y_mm,Z_mm\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,1,1,0\n";
        let flat = Template::from_str("t.csv", text).unwrap();
        assert_eq!(flat.leds[2].z_mm, Some(0.0));
        assert!(!flat.is_three_d());
        let text = "led,X_mm,Y_mm,Z_mm\n1,0,0,0\n2,1,0,2.5\n3,0,1,-1e3\n4,1,1,0\n";
        let t = Template::from_str("t.csv", text).unwrap();
        assert_eq!(t.leds[1].z_mm, Some(2.5));
        assert_eq!(t.leds[2].z_mm, Some(-1000.0));
        assert!(t.is_three_d());
        let text = "led,X_mm,Y_mm,Z_mm\n1,0,0,0\n2,1,0,\n3,0,1,0\n4,1,1,0\n";
        let e = Template::from_str("t.csv", text).unwrap_err();
        assert_eq!(e.line(), Some(3));
        assert!(e.to_string().contains("Z_mm"), "{e}");
    }

    #[test]
    fn too_few_leds() {
        let text = "led,X_mm,Y_mm\n1,0,0\n2,1,0\n3,0,1\n";
        let e = Template::from_str("template.csv", text).unwrap_err();
        assert_eq!(
            e.to_string(),
            "template.csv: the template has 3 LEDs; expected at least 4"
        );
    }

    #[test]
    fn non_finite_and_bad_values() {
        let text = "led,X_mm,Y_mm\n1,0,0\n2,inf,0\n";
        let e = Template::from_str("template.csv", text).unwrap_err();
        assert_eq!(
            e.to_string(),
            "template.csv:3: column 'X_mm' (2): expected a finite number, found an infinite value \
             'inf'"
        );
        let text = "led,X_mm,Y_mm\n1,0,0\n2,1,nan\n";
        let e = Template::from_str("template.csv", text).unwrap_err();
        assert_eq!(e.line(), Some(3));
        assert!(matches!(e, IoError::Value { ref column, .. } if column.number == 3));
        let text = "led,X_mm,Y_mm\n,0,0\n";
        let e = Template::from_str("template.csv", text).unwrap_err();
        assert_eq!(
            e.to_string(),
            "template.csv:2: column 'led' (1): expected an LED identifier, found an empty field"
        );
    }

    #[test]
    fn missing_column_and_header_only() {
        let e = Template::from_str("template.csv", "led,X_mm\n1,2\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "template.csv:1: missing column 'Y_mm'; expected the columns led, X_mm, Y_mm (and \
             optionally lines) (the header has: led, X_mm)"
        );
        let e = Template::from_str("template.csv", "led,X_mm,Y_mm\n").unwrap_err();
        assert_eq!(e.line(), Some(1));
    }

    #[test]
    fn reads_from_a_file_and_a_reader() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("template.csv");
        std::fs::write(&path, VALID).unwrap();
        let t = Template::read(&path).unwrap();
        assert_eq!(t.source, path.display().to_string());
        assert_eq!(t.leds.len(), 6);
        let r = Template::from_reader("r.csv", VALID.as_bytes()).unwrap();
        assert_eq!(r.leds, t.leds);
        let e = Template::read(dir.path().join("missing.csv")).unwrap_err();
        assert!(matches!(e, IoError::Read { .. }));
        assert!(e.to_string().contains("missing.csv: cannot read the file"));
    }
}
