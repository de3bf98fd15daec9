//! Every point's residuals, computed once: on the template plane
//! (back-projected point − LED) and on the sensor (projected LED − measured
//! point), mm. They feed residuals.csv and the report's plots and tables.

use std::io::Write;
use std::path::Path;

use nalgebra::Vector2;
use psdcal_io::{write_atomic, Template, ValidatedDataSet};
use psdcal_model::{Model, Pose};

use crate::base::error::Result;

/// One point's residuals.
#[derive(Debug, Clone, PartialEq)]
pub struct Residual {
    /// LED index in the template.
    pub led: usize,
    /// Measured point, mm.
    pub measured: Vector2<f64>,
    /// LED on the template, mm.
    pub template: Vector2<f64>,
    /// Template-plane error, mm (`None` when the point cannot be
    /// back-projected).
    pub on_template: Option<Vector2<f64>>,
    /// Sensor error, mm (`None` when the LED cannot be projected).
    pub on_sensor: Option<Vector2<f64>>,
}

/// One image's residuals (`None` when the image has no pose).
#[derive(Debug, Clone, PartialEq)]
pub struct ImageResiduals {
    /// Identifier.
    pub id: String,
    /// Points of the image.
    pub points: usize,
    /// The residuals, when the image has a pose.
    pub residuals: Option<Vec<Residual>>,
}

impl ImageResiduals {
    /// RMS of the template-plane and sensor errors, mm (`None` without
    /// any).
    pub fn rms(&self) -> (Option<f64>, Option<f64>) {
        let rms = |errors: Vec<Vector2<f64>>| {
            (!errors.is_empty()).then(|| {
                (errors.iter().map(|e| e.norm_squared()).sum::<f64>() / errors.len() as f64).sqrt()
            })
        };
        let Some(r) = &self.residuals else {
            return (None, None);
        };
        (
            rms(r.iter().filter_map(|p| p.on_template).collect()),
            rms(r.iter().filter_map(|p| p.on_sensor).collect()),
        )
    }
}

/// The residuals of every image of a data set.
#[derive(Debug, Clone, PartialEq)]
pub struct ResidualTable {
    /// Per image, in data-set order.
    pub images: Vec<ImageResiduals>,
}

impl ResidualTable {
    /// Computes the residuals of `set` under `model`, each image at the
    /// pose of the same id (images without one get none).
    pub fn compute(
        model: &Model,
        poses: &[(&str, Pose)],
        template: &Template,
        set: &ValidatedDataSet,
    ) -> Self {
        let images = set
            .images
            .iter()
            .map(|image| {
                let pose = poses.iter().find(|(id, _)| *id == image.id).map(|(_, p)| p);
                ImageResiduals {
                    id: image.id.clone(),
                    points: image.points.len(),
                    residuals: pose.map(|pose| {
                        image
                            .points
                            .iter()
                            .map(|&(led, measured)| {
                                let l = &template.leds[led];
                                let xy = Vector2::new(l.x_mm, l.y_mm);
                                Residual {
                                    led,
                                    measured,
                                    template: xy,
                                    on_template: model
                                        .back_project(pose, &measured)
                                        .ok()
                                        .map(|p| p - xy),
                                    on_sensor: model.project(pose, &xy).ok().map(|p| p - measured),
                                }
                            })
                            .collect()
                    }),
                }
            })
            .collect();
        Self { images }
    }

    /// Writes residuals.csv atomically: `image, led, x_mm, y_mm, X_mm, Y_mm,
    /// template_dx_mm, template_dy_mm, image_dx_mm, image_dy_mm`.
    pub fn write_csv(&self, path: &Path, template: &Template) -> Result<()> {
        Ok(write_atomic(path, |w| self.write_rows(w, template))?)
    }

    /// Writes the table's CSV text (header and rows) to `w`.
    pub fn write_rows(&self, w: &mut impl Write, template: &Template) -> std::io::Result<()> {
        writeln!(
            w,
            "image,led,x_mm,y_mm,X_mm,Y_mm,template_dx_mm,template_dy_mm,image_dx_mm,image_dy_mm"
        )?;
        for image in &self.images {
            for r in image.residuals.iter().flatten() {
                let fmt = |v: Option<f64>| v.map(|v| format!("{v:e}")).unwrap_or_default();
                writeln!(
                    w,
                    "{},{},{:e},{:e},{},{},{},{},{},{}",
                    psdcal_io::csv_field(&image.id),
                    psdcal_io::csv_field(&template.leds[r.led].id),
                    r.measured.x,
                    r.measured.y,
                    r.template.x,
                    r.template.y,
                    fmt(r.on_template.map(|d| d.x)),
                    fmt(r.on_template.map(|d| d.y)),
                    fmt(r.on_sensor.map(|d| d.x)),
                    fmt(r.on_sensor.map(|d| d.y)),
                )?;
            }
        }
        Ok(())
    }
}
