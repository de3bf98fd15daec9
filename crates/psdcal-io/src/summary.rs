//! A summary of a validated data set, for `psdcal check` and reports: the
//! template, the images with their point counts and ranges, what was dropped
//! and why, and the coverage of the sensor ([`Coverage`]). It serialises to
//! JSON with named fields in millimetres.

use psdcal_model::PsdGeometry;
use serde::Serialize;

use crate::calibration::SensorSize;
use crate::coverage::{Bounds, Coverage};
use crate::template::Template;
use crate::validate::ValidatedDataSet;
use crate::warning::Warning;

/// The template part of a summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TemplateSummary {
    /// Template file.
    pub file: String,
    /// Number of LEDs.
    pub leds: usize,
    /// Declared line groups.
    pub lines: Vec<LineSummary>,
}

/// One declared line group.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct LineSummary {
    /// Its label.
    pub name: String,
    /// Its number of LEDs.
    pub leds: usize,
}

/// One usable image.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImageSummary {
    /// Image identifier.
    pub id: String,
    /// Usable points.
    pub points: usize,
    /// Bounding box of its points.
    pub bounds: Option<Bounds>,
}

/// A data set at a glance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DataSetSummary {
    /// The template.
    pub template: TemplateSummary,
    /// Observations (or signals) file.
    pub observations_file: String,
    /// Rows in that file.
    pub rows: usize,
    /// Active area used for the checks.
    pub sensor: SensorSize,
    /// Usable images, in file order.
    pub images: Vec<ImageSummary>,
    /// Usable points over all images.
    pub total_points: usize,
    /// Points dropped because they were off the active area or in a dropped
    /// image.
    pub dropped_points: usize,
    /// Images dropped for having too few points.
    pub dropped_images: usize,
    /// Coverage of the active area by the usable points.
    pub coverage: Coverage,
    /// Every warning, template first.
    pub warnings: Vec<Warning>,
}

impl DataSetSummary {
    /// Summarises a validated data set whose points file `points_file`
    /// held `rows` rows.
    pub fn new(
        template: &Template,
        points_file: &str,
        rows: usize,
        set: &ValidatedDataSet,
        geometry: &PsdGeometry,
    ) -> Self {
        let images: Vec<ImageSummary> = set
            .images
            .iter()
            .map(|image| ImageSummary {
                id: image.id.clone(),
                points: image.points.len(),
                bounds: Bounds::of(image.points.iter().map(|(_, p)| p)),
            })
            .collect();
        let all = set
            .images
            .iter()
            .flat_map(|image| image.points.iter().map(|(_, p)| p));
        let total_points = set.total_points();
        let dropped_images = set
            .warnings
            .iter()
            .filter(|w| matches!(w, Warning::TooFewPoints { .. }))
            .count();
        Self {
            template: TemplateSummary {
                file: template.source.clone(),
                leds: template.leds.len(),
                lines: template
                    .line_groups()
                    .into_iter()
                    .map(|g| LineSummary {
                        name: g.name,
                        leds: g.leds.len(),
                    })
                    .collect(),
            },
            observations_file: points_file.to_string(),
            rows,
            sensor: SensorSize {
                lx_mm: geometry.lx,
                ly_mm: geometry.ly,
            },
            images,
            total_points,
            dropped_points: rows.saturating_sub(total_points),
            dropped_images,
            coverage: Coverage::of(all, geometry, Coverage::DEFAULT_CELLS),
            warnings: set.warnings.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observations::Observations;
    use crate::validate::{validate_data_set, ValidationOptions};

    #[test]
    fn summarises_images_drops_and_coverage() {
        let template = Template::from_str(
            "template.csv",
            "led,X_mm,Y_mm,lines\n1,0,0,a\n2,1,0,a\n3,2,0,a\n4,0,1,\n5,1,1,\n",
        )
        .unwrap();
        let mut text = String::from("image,led,x_mm,y_mm\n");
        // Image A: 5 points, one off the sensor → 4 kept.
        for (led, x, y) in [
            (1, -4.0, -4.0),
            (2, 4.0, -4.0),
            (3, 4.0, 4.0),
            (4, -4.0, 4.0),
        ] {
            text.push_str(&format!("A,{led},{x},{y}\n"));
        }
        text.push_str("A,5,9,0\n");
        // Image B: 3 points → dropped.
        for led in 1..=3 {
            text.push_str(&format!("B,{led},0.1,0.1\n"));
        }
        let obs = Observations::from_str("obs.csv", &text).unwrap();
        let set = validate_data_set(&template, &obs, &ValidationOptions::default()).unwrap();
        let s = DataSetSummary::new(
            &template,
            &obs.source,
            obs.rows.len(),
            &set,
            &PsdGeometry::default(),
        );
        assert_eq!(s.template.leds, 5);
        assert_eq!(
            s.template.lines,
            vec![LineSummary {
                name: "a".into(),
                leds: 3
            }]
        );
        assert_eq!(s.observations_file, "obs.csv");
        assert_eq!(s.rows, 8);
        assert_eq!(s.images.len(), 1);
        assert_eq!(s.images[0].id, "A");
        assert_eq!(s.images[0].points, 4);
        assert_eq!(
            s.images[0].bounds,
            Some(Bounds {
                x_min_mm: -4.0,
                x_max_mm: 4.0,
                y_min_mm: -4.0,
                y_max_mm: 4.0
            })
        );
        assert_eq!(s.total_points, 4);
        assert_eq!(s.dropped_points, 4);
        assert_eq!(s.dropped_images, 1);
        assert_eq!(s.coverage.cells_covered, 4);
        assert_eq!(s.coverage.fraction, 0.04);
        // Off-sensor point, too few points, too few images.
        assert_eq!(s.warnings.len(), 3);
        let json = serde_json::to_value(&s).unwrap();
        assert_eq!(json["warnings"][0]["kind"], "point_off_sensor");
        assert_eq!(json["warnings"][0]["line"], 6);
        assert_eq!(json["images"][0]["bounds"]["x_max_mm"], 4.0);
        assert_eq!(json["coverage"]["counts"][0][0], 1);
    }
}
