//! Warnings: suspicious data psdcal worked around (a point dropped, an
//! image dropped, a short line group, a point corrected outside the area
//! the model was fitted on). Each names its file and, where there is one,
//! its line; [`Warning::problem`] says what is wrong and
//! [`Warning::consequence`] what psdcal did about it. Warnings serialise to
//! JSON with a `kind` tag and their fields.

use std::fmt;

use serde::Serialize;

use crate::location::Location;

/// Something suspicious in the data that psdcal worked around.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[non_exhaustive]
pub enum Warning {
    /// A measured point lies off the active area; it was dropped.
    PointOffSensor {
        /// Observations file.
        file: String,
        /// Line of the row.
        line: usize,
        /// Image identifier.
        image: String,
        /// LED identifier.
        led: String,
        /// The point, mm.
        x_mm: f64,
        /// The point, mm.
        y_mm: f64,
        /// Active area side along x, mm.
        lx_mm: f64,
        /// Active area side along y, mm.
        ly_mm: f64,
    },
    /// An image has too few usable points; it was dropped.
    TooFewPoints {
        /// Observations file.
        file: String,
        /// Line of the image's first row.
        line: usize,
        /// Image identifier.
        image: String,
        /// Usable points left.
        count: usize,
        /// Points needed.
        min: usize,
    },
    /// Fewer usable images than a calibration needs.
    TooFewImages {
        /// Observations file.
        file: String,
        /// Usable images.
        count: usize,
        /// Images needed.
        min: usize,
    },
    /// A template line group is too short to constrain straightness.
    ShortLineGroup {
        /// Template file.
        file: String,
        /// The group's label.
        group: String,
        /// Lines of its LEDs.
        lines: Vec<usize>,
        /// LEDs needed.
        min: usize,
    },
    /// A point to correct lies off the active area, where the model was not
    /// fitted; it was corrected anyway.
    PointOutsideArea {
        /// Points file.
        file: String,
        /// Line of the row.
        line: usize,
        /// The point, mm.
        x_mm: f64,
        /// The point, mm.
        y_mm: f64,
        /// Active area side along x, mm.
        lx_mm: f64,
        /// Active area side along y, mm.
        ly_mm: f64,
    },
}

impl Warning {
    /// The file the warning is about.
    pub fn file(&self) -> &str {
        match self {
            Warning::PointOffSensor { file, .. }
            | Warning::TooFewPoints { file, .. }
            | Warning::TooFewImages { file, .. }
            | Warning::ShortLineGroup { file, .. }
            | Warning::PointOutsideArea { file, .. } => file,
        }
    }

    /// The 1-based line the warning is about, if any.
    pub fn line(&self) -> Option<usize> {
        match self {
            Warning::PointOffSensor { line, .. }
            | Warning::TooFewPoints { line, .. }
            | Warning::PointOutsideArea { line, .. } => Some(*line),
            Warning::ShortLineGroup { lines, .. } => lines.first().copied(),
            Warning::TooFewImages { .. } => None,
        }
    }

    fn location(&self) -> Location {
        Location {
            file: self.file().to_string(),
            line: self.line(),
        }
    }
}

fn plural(count: usize, one: &str, many: &str) -> String {
    if count == 1 {
        format!("{count} {one}")
    } else {
        format!("{count} {many}")
    }
}

impl Warning {
    /// What is wrong, with its location, without what psdcal did about it.
    pub fn problem(&self) -> String {
        let at = self.location();
        match self {
            Warning::PointOffSensor {
                image,
                led,
                x_mm,
                y_mm,
                lx_mm,
                ly_mm,
                ..
            } => format!(
                "{at}: image '{image}', LED '{led}': point ({x_mm}, {y_mm}) mm is off the \
                 {lx_mm} x {ly_mm} mm active area"
            ),
            Warning::TooFewPoints {
                image, count, min, ..
            } => format!(
                "{at}: image '{image}' has {} on the sensor; expected at least {min}",
                plural(*count, "point", "points")
            ),
            Warning::TooFewImages { count, min, .. } => format!(
                "{at}: {}; a calibration needs at least {min}",
                plural(*count, "usable image", "usable images")
            ),
            Warning::ShortLineGroup {
                group, lines, min, ..
            } => {
                let list: Vec<String> = lines.iter().map(usize::to_string).collect();
                format!(
                    "{at}: line group '{group}' has {} (lines {}); expected at least {min}",
                    plural(lines.len(), "LED", "LEDs"),
                    list.join(", ")
                )
            }
            Warning::PointOutsideArea {
                x_mm,
                y_mm,
                lx_mm,
                ly_mm,
                ..
            } => format!(
                "{at}: point ({x_mm}, {y_mm}) mm is off the {lx_mm} x {ly_mm} mm active area, \
                 where the model was not fitted"
            ),
        }
    }

    /// What psdcal did about it.
    pub fn consequence(&self) -> &'static str {
        match self {
            Warning::PointOffSensor { .. } => "point dropped",
            Warning::TooFewPoints { .. } => "image dropped",
            Warning::TooFewImages { .. } => "checked anyway",
            Warning::ShortLineGroup { .. } => "it cannot constrain straightness",
            Warning::PointOutsideArea { .. } => "corrected anyway",
        }
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.problem(), self.consequence())
    }
}
