//! Validation of a calibration data set: a template plus the observations of
//! several images (docs/formats.md, docs/model.md §4 "Input").
//!
//! Errors (the data set cannot be used as it is):
//! - an observation names an LED the template does not have;
//! - the same (image, LED) pair appears twice (both lines are named);
//! - no image is left with enough points.
//!
//! Warnings (the offending data are dropped, the rest is usable):
//! - a point off the sensor's active area (`psdcal_model::psd::is_on_active_area`);
//! - an image with fewer than [`MIN_POINTS_PER_IMAGE`] points left;
//! - fewer than [`MIN_IMAGES`] usable images;
//! - a template line group with fewer than 3 LEDs (see [`Template::warnings`]).
//!
//! With [`ValidationOptions::strict`] the first warning becomes an error.

use std::collections::HashMap;

use nalgebra::Vector2;
use psdcal_model::psd::is_on_active_area;
use psdcal_model::PsdGeometry;

use crate::error::IoError;
use crate::location::Location;
use crate::observations::{ObservationText, Observations};
use crate::template::Template;
use crate::warning::Warning;

pub use psdcal_model::fit::{MIN_IMAGES, MIN_POINTS_PER_IMAGE};

/// How to validate a data set.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ValidationOptions {
    /// The sensor's active area (default 9 × 9 mm).
    pub geometry: PsdGeometry,
    /// Turn every warning into an error.
    pub strict: bool,
}

/// The usable measured points of one image.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Image identifier.
    pub id: String,
    /// `(index into Template::leds, measured point in mm)`, in file order.
    pub points: Vec<(usize, Vector2<f64>)>,
}

/// A data set ready for calibration, and what was dropped on the way.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidatedDataSet {
    /// Usable images, in order of first appearance in the file.
    pub images: Vec<Image>,
    /// Warnings, template first, then in file order.
    pub warnings: Vec<Warning>,
}

impl ValidatedDataSet {
    /// Number of usable points over all images.
    pub fn total_points(&self) -> usize {
        self.images.iter().map(|i| i.points.len()).sum()
    }
}

/// Checks observations against a template and groups them by image.
pub fn validate_data_set(
    template: &Template,
    observations: &Observations,
    options: &ValidationOptions,
) -> Result<ValidatedDataSet, IoError> {
    let mut validator = DataSetValidator::new(template, &observations.source, options);
    for row in &observations.rows {
        validator.push(&ObservationText {
            image: &row.image,
            led: &row.led,
            x_mm: row.x_mm,
            y_mm: row.y_mm,
            line_no: row.line_no,
        })?;
    }
    validator.finish()
}

/// An image being collected.
struct ImageRows {
    id: String,
    first_line: usize,
    points: Vec<(usize, Vector2<f64>)>,
    /// `(LED index, line)` of every row, on the sensor or not, for the
    /// duplicate check (sorted once at the end: no map grows with the rows).
    rows: Vec<(u32, u32)>,
}

/// [`validate_data_set`] one row at a time, as a file is read: memory
/// follows the usable points (numbers), not the file's text.
pub struct DataSetValidator<'t> {
    template: &'t Template,
    source: String,
    options: ValidationOptions,
    led_index: HashMap<&'t str, usize>,
    images: Vec<ImageRows>,
    image_index: HashMap<String, usize>,
    warnings: Vec<Warning>,
    rows: usize,
}

impl<'t> DataSetValidator<'t> {
    /// A validator of the rows of `source` against `template`.
    pub fn new(template: &'t Template, source: &str, options: &ValidationOptions) -> Self {
        let led_index = template
            .leds
            .iter()
            .enumerate()
            .map(|(i, led)| (led.id.as_str(), i))
            .collect();
        Self {
            template,
            source: source.to_string(),
            options: *options,
            led_index,
            images: Vec::new(),
            image_index: HashMap::new(),
            warnings: template.warnings(),
            rows: 0,
        }
    }

    /// The rows seen so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Checks one row: an unknown LED is an error (or the duplicate before
    /// it, to report the first fault in file order); a point off the
    /// sensor is dropped with a warning.
    pub fn push(&mut self, row: &ObservationText<'_>) -> Result<(), IoError> {
        self.rows += 1;
        let Some(&led) = self.led_index.get(row.led) else {
            self.check_duplicates()?;
            return Err(IoError::UnknownLed {
                at: Location::line(&self.source, row.line_no),
                led: row.led.to_string(),
                template: self.template.source.clone(),
            });
        };
        let slot = self.slot(row);
        let image = &mut self.images[slot];
        image.rows.push((led_key(led), line_key(row.line_no)));
        let point = Vector2::new(row.x_mm, row.y_mm);
        let geometry = &self.options.geometry;
        if is_on_active_area(geometry, &point) {
            image.points.push((led, point));
        } else {
            self.warnings.push(Warning::PointOffSensor {
                file: self.source.clone(),
                line: row.line_no,
                image: row.image.to_string(),
                led: row.led.to_string(),
                x_mm: row.x_mm,
                y_mm: row.y_mm,
                lx_mm: geometry.lx,
                ly_mm: geometry.ly,
            });
        }
        Ok(())
    }

    /// The usable images and the warnings, or the first fault.
    pub fn finish(mut self) -> Result<ValidatedDataSet, IoError> {
        self.check_duplicates()?;
        let source = self.source;
        let mut warnings = self.warnings;
        let mut usable = Vec::with_capacity(self.images.len());
        for image in self.images {
            if image.points.len() < MIN_POINTS_PER_IMAGE {
                warnings.push(Warning::TooFewPoints {
                    file: source.clone(),
                    line: image.first_line,
                    image: image.id,
                    count: image.points.len(),
                    min: MIN_POINTS_PER_IMAGE,
                });
            } else {
                usable.push(Image {
                    id: image.id,
                    points: image.points,
                });
            }
        }
        if !usable.is_empty() && usable.len() < MIN_IMAGES {
            warnings.push(Warning::TooFewImages {
                file: source.clone(),
                count: usable.len(),
                min: MIN_IMAGES,
            });
        }
        if self.options.strict {
            if let Some(warning) = warnings.first() {
                return Err(IoError::Strict {
                    warning: warning.clone(),
                });
            }
        }
        if usable.is_empty() {
            return Err(IoError::Invalid {
                at: Location::file(&source),
                message: format!(
                    "no usable image: expected at least one image with {MIN_POINTS_PER_IMAGE} \
                     points on the sensor"
                ),
            });
        }
        Ok(ValidatedDataSet {
            images: usable,
            warnings,
        })
    }

    /// The image slot of a row, a new one for a new image.
    fn slot(&mut self, row: &ObservationText<'_>) -> usize {
        if let Some(&slot) = self.image_index.get(row.image) {
            return slot;
        }
        self.images.push(ImageRows {
            id: row.image.to_string(),
            first_line: row.line_no,
            points: Vec::new(),
            rows: Vec::new(),
        });
        self.image_index
            .insert(row.image.to_string(), self.images.len() - 1);
        self.images.len() - 1
    }

    /// The first row (in file order) whose (image, LED) pair came before:
    /// each image's rows sorted by (LED, line), a pair's second row is its
    /// earliest repeat.
    fn check_duplicates(&mut self) -> Result<(), IoError> {
        let mut first: Option<(u32, u32, usize, u32)> = None; // (line, first line, image, led)
        for (slot, image) in self.images.iter_mut().enumerate() {
            image.rows.sort_unstable();
            for pair in image.rows.windows(2) {
                let ((led, line_a), (led_b, line_b)) = (pair[0], pair[1]);
                if led == led_b && first.is_none_or(|(line, ..)| line_b < line) {
                    first = Some((line_b, line_a, slot, led));
                }
            }
        }
        let Some((line, first_line, slot, led)) = first else {
            return Ok(());
        };
        let image = &self.images[slot].id;
        let led = &self.template.leds[led as usize].id;
        Err(IoError::Duplicate {
            at: Location::line(&self.source, line as usize),
            first_line: first_line as usize,
            what: format!("image '{image}', LED '{led}'"),
        })
    }
}

/// An LED index as stored per row (templates hold far fewer than 2³² LEDs).
fn led_key(led: usize) -> u32 {
    u32::try_from(led).unwrap_or(u32::MAX)
}

/// A line number as stored per row: files past 2³² lines (tens of GB, far
/// beyond the read limits) report the last representable line.
fn line_key(line: usize) -> u32 {
    u32::try_from(line).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEMPLATE: &str = "\
led,X_mm,Y_mm,lines
1,0,0,r1
2,10,0,r1
3,20,0,r1
4,0,10,r2
5,10,10,r2
6,20,10,r2
";

    fn template() -> Template {
        Template::from_str("template.csv", TEMPLATE).unwrap()
    }

    /// An observations file: a header, then for each image its LEDs
    /// 1..=count at (0.5 led, −0.25 led) mm.
    fn observations(images: &[(&str, usize)]) -> String {
        let mut text = String::from("image,led,x_mm,y_mm\n");
        for (image, count) in images {
            for led in 1..=*count {
                let (x, y) = (0.5 * led as f64, -0.25 * led as f64);
                text.push_str(&format!("{image},{led},{x},{y}\n"));
            }
        }
        text
    }

    fn validate(text: &str, strict: bool) -> Result<ValidatedDataSet, IoError> {
        let obs = Observations::from_str("observations.csv", text).unwrap();
        let options = ValidationOptions {
            strict,
            ..ValidationOptions::default()
        };
        validate_data_set(&template(), &obs, &options)
    }

    #[test]
    fn groups_points_by_image_in_file_order() {
        let set = validate(&observations(&[("b", 4), ("a", 6), ("c", 5)]), false).unwrap();
        let ids: Vec<&str> = set.images.iter().map(|i| i.id.as_str()).collect();
        assert_eq!(ids, ["b", "a", "c"]);
        assert_eq!(set.images[1].points.len(), 6);
        assert_eq!(set.images[1].points[2], (2, Vector2::new(1.5, -0.75)));
        assert_eq!(set.total_points(), 15);
        assert!(set.warnings.is_empty(), "{:?}", set.warnings);
    }

    #[test]
    fn interleaved_rows_join_their_image() {
        let text = "image,led,x_mm,y_mm\n1,1,0,0\n2,1,0,0\n1,2,1,0\n2,2,1,0\n1,3,0,1\n\
                    2,3,0,1\n1,4,1,1\n2,4,1,1\n3,1,0,0\n3,2,1,0\n3,3,0,1\n3,4,1,1\n";
        let set = validate(text, true).unwrap();
        assert_eq!(set.images.len(), 3);
        let leds: Vec<usize> = set.images[1].points.iter().map(|p| p.0).collect();
        assert_eq!(leds, [0, 1, 2, 3]);
    }

    #[test]
    fn unknown_led_is_an_error_naming_line_and_id() {
        let mut text = observations(&[("1", 4)]);
        text.push_str("1,99,0,0\n");
        let e = validate(&text, false).unwrap_err();
        assert_eq!(
            e.to_string(),
            "observations.csv:6: LED '99' is not in the template template.csv; expected one of \
             its LED ids"
        );
    }

    #[test]
    fn duplicate_pair_names_both_lines() {
        let text = "image,led,x_mm,y_mm\n1,1,0,0\n1,2,0,0\n\n# again\n1,1,0.5,0\n";
        let e = validate(text, false).unwrap_err();
        assert_eq!(
            e.to_string(),
            "observations.csv:6: image '1', LED '1' appears twice (first on line 2)"
        );
        // The same LED in two images is fine.
        assert!(validate(&observations(&[("1", 4), ("2", 4), ("3", 4)]), true).is_ok());
    }

    #[test]
    fn off_sensor_point_is_dropped_with_a_warning() {
        let mut text = observations(&[("1", 4), ("2", 4), ("3", 4)]);
        text.push_str("3,5,4.5,-4.5\n3,6,4.6,0\n");
        let set = validate(&text, false).unwrap();
        // (4.5, -4.5) is on the closed boundary, (4.6, 0) is off.
        assert_eq!(set.images[2].points.len(), 5);
        assert_eq!(
            set.warnings,
            vec![Warning::PointOffSensor {
                file: "observations.csv".into(),
                line: 15,
                image: "3".into(),
                led: "6".into(),
                x_mm: 4.6,
                y_mm: 0.0,
                lx_mm: 9.0,
                ly_mm: 9.0,
            }]
        );
        assert_eq!(
            set.warnings[0].to_string(),
            "observations.csv:15: image '3', LED '6': point (4.6, 0) mm is off the 9 x 9 mm \
             active area: point dropped"
        );
    }

    #[test]
    fn smaller_geometry_drops_more() {
        let obs = Observations::from_str("o.csv", &observations(&[("1", 6)])).unwrap();
        let options = ValidationOptions {
            geometry: PsdGeometry { lx: 4.0, ly: 4.0 },
            strict: false,
        };
        let set = validate_data_set(&template(), &obs, &options).unwrap();
        // x = 0.5 .. 3 mm: LEDs 5 and 6 (x = 2.5, 3 > 2) are off.
        let leds: Vec<usize> = set.images[0].points.iter().map(|p| p.0).collect();
        assert_eq!(leds, [0, 1, 2, 3]);
        let lines: Vec<Option<usize>> = set.warnings.iter().map(Warning::line).collect();
        assert_eq!(lines, [Some(6), Some(7), None]);
        assert!(matches!(
            set.warnings[2],
            Warning::TooFewImages { count: 1, .. }
        ));
    }

    #[test]
    fn image_with_three_points_is_dropped_with_a_warning() {
        let text = observations(&[("1", 4), ("2", 3), ("3", 4), ("4", 4)]);
        let set = validate(&text, false).unwrap();
        let ids: Vec<&str> = set.images.iter().map(|i| i.id.as_str()).collect();
        assert_eq!(ids, ["1", "3", "4"]);
        assert_eq!(
            set.warnings,
            vec![Warning::TooFewPoints {
                file: "observations.csv".into(),
                line: 6,
                image: "2".into(),
                count: 3,
                min: 4,
            }]
        );
        assert_eq!(
            set.warnings[0].to_string(),
            "observations.csv:6: image '2' has 3 points on the sensor; expected at least 4: \
             image dropped"
        );
        let e = validate(&text, true).unwrap_err();
        assert_eq!(e.line(), Some(6));
        assert_eq!(
            e.to_string(),
            "observations.csv:6: image '2' has 3 points on the sensor; expected at least 4 \
             (strict validation makes this warning an error)"
        );
    }

    #[test]
    fn too_few_images_warns_and_none_is_an_error() {
        let set = validate(&observations(&[("1", 4), ("2", 5)]), false).unwrap();
        assert_eq!(
            set.warnings,
            vec![Warning::TooFewImages {
                file: "observations.csv".into(),
                count: 2,
                min: 3
            }]
        );
        assert_eq!(
            set.warnings[0].to_string(),
            "observations.csv: 2 usable images; a calibration needs at least 3: checked anyway"
        );
        let e = validate(&observations(&[("1", 3)]), false).unwrap_err();
        assert_eq!(
            e.to_string(),
            "observations.csv: no usable image: expected at least one image with 4 points on the \
             sensor"
        );
    }

    #[test]
    fn template_warnings_come_first_and_are_errors_when_strict() {
        let text = "led,X_mm,Y_mm,lines\n1,0,0,a\n2,1,0,a\n3,0,1,\n4,1,1,\n";
        let t = Template::from_str("template.csv", text).unwrap();
        let obs = Observations::from_str("o.csv", &observations(&[("1", 4), ("2", 4), ("3", 4)]))
            .unwrap();
        let set = validate_data_set(&t, &obs, &ValidationOptions::default()).unwrap();
        assert_eq!(set.warnings.len(), 1);
        assert_eq!(set.warnings[0].line(), Some(2));
        assert_eq!(set.warnings[0].file(), "template.csv");
        let strict = ValidationOptions {
            strict: true,
            ..ValidationOptions::default()
        };
        let e = validate_data_set(&t, &obs, &strict).unwrap_err();
        assert_eq!(e.file(), Some("template.csv"));
        assert_eq!(e.line(), Some(2));
    }
}
