//! The input of a calibration: a planar template of LEDs and, per image
//! (template pose), the measured impact points of the LEDs seen in it
//! (docs/model.md §4).

use nalgebra::Vector2;
use psdcal_model::{Amplitudes, PsdGeometry};

use crate::CalibError;

/// One measured impact point of one LED in one image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Index of the LED in [`CalibrationData::template`].
    pub led: usize,
    /// Measured impact point, mm, sensor frame.
    pub measured: Vector2<f64>,
}

/// The observations of one image (one template pose).
#[derive(Debug, Clone, PartialEq)]
pub struct ImageObservations {
    /// The image's identifier, as in the input files.
    pub id: String,
    /// Its points (each LED at most once).
    pub points: Vec<Observation>,
}

/// Everything a calibration is computed from.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationData {
    /// LED positions `(X, Y)` on the template plane, mm.
    pub template: Vec<Vector2<f64>>,
    /// Collinear groups of LEDs (indices into `template`, ≥ 3 each), for the
    /// line-straightness correction; empty when the template declares none.
    pub lines: Vec<Vec<usize>>,
    /// The images.
    pub images: Vec<ImageObservations>,
    /// The PSD's active area.
    pub geometry: PsdGeometry,
    /// The electrode amplitudes behind every point (`[image][point]`, same
    /// order as `images`), when the data came as signals: needed to estimate
    /// the channel gains, which recompute each impact point from its
    /// amplitudes (docs/model.md §1). `measured` then holds the points computed
    /// with the starting gains.
    pub amplitudes: Option<Vec<Vec<Amplitudes>>>,
    /// Per image and point (same order as `images`), the variance of the
    /// point's channel noise relative to the others', when each record has
    /// its own SNR (`10^(−SNR/10)` from signals.csv's `snr_db`): the
    /// `channel-snr` noise model scales the point's covariance by it
    /// ([`crate::weighting`]). Ignored by the other noise models.
    pub noise_scale: Option<Vec<Vec<f64>>>,
}

impl CalibrationData {
    /// The data of `points[image][led]`: every LED of `template` seen in
    /// every image, images named `1, 2, …`, on a PSD of `geometry`, no
    /// amplitudes.
    pub fn from_points(
        template: &[Vector2<f64>],
        lines: &[Vec<usize>],
        points: Vec<Vec<Vector2<f64>>>,
        geometry: PsdGeometry,
    ) -> Self {
        let images = points
            .into_iter()
            .enumerate()
            .map(|(i, image)| ImageObservations {
                id: format!("{}", i + 1),
                points: image
                    .into_iter()
                    .enumerate()
                    .map(|(led, measured)| Observation { led, measured })
                    .collect(),
            })
            .collect();
        Self {
            amplitudes: None,
            noise_scale: None,
            template: template.to_vec(),
            lines: lines.to_vec(),
            images,
            geometry,
        }
    }

    /// Checks what every routine relies on: finite template and measured
    /// points, LED indices inside the template, each LED at most once per
    /// image, declared lines naming existing LEDs. (Files are validated by
    /// psdcal-io before they become `CalibrationData`; this guards data built
    /// in memory.)
    pub fn check(&self) -> Result<(), CalibError> {
        if !self
            .template
            .iter()
            .all(|p| p.x.is_finite() && p.y.is_finite())
        {
            return Err(CalibError::InvalidInput {
                reason: "the template has non-finite LED coordinates".into(),
            });
        }
        for im in &self.images {
            let mut seen = vec![false; self.template.len()];
            for o in &im.points {
                if o.led >= self.template.len() {
                    return Err(CalibError::UnknownLed {
                        led: o.led,
                        template_len: self.template.len(),
                    });
                }
                if seen[o.led] {
                    return Err(CalibError::InvalidInput {
                        reason: format!("image '{}' has LED {} more than once", im.id, o.led),
                    });
                }
                seen[o.led] = true;
                if !(o.measured.x.is_finite() && o.measured.y.is_finite()) {
                    return Err(CalibError::InvalidInput {
                        reason: format!(
                            "image '{}' has a non-finite point for LED {}",
                            im.id, o.led
                        ),
                    });
                }
            }
        }
        for line in &self.lines {
            if let Some(&led) = line.iter().find(|&&l| l >= self.template.len()) {
                return Err(CalibError::UnknownLed {
                    led,
                    template_len: self.template.len(),
                });
            }
        }
        if let Some(scale) = &self.noise_scale {
            let fits = scale.len() == self.images.len()
                && scale
                    .iter()
                    .zip(&self.images)
                    .all(|(s, im)| s.len() == im.points.len());
            if !fits || scale.iter().flatten().any(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(CalibError::InvalidInput {
                    reason: "the per-point noise scales must match the points and be finite and \
                             positive"
                        .into(),
                });
            }
        }
        Ok(())
    }

    /// Whether amplitudes are present for every point.
    pub fn has_amplitudes(&self) -> bool {
        self.amplitudes.as_ref().is_some_and(|a| {
            a.len() == self.images.len()
                && a.iter()
                    .zip(&self.images)
                    .all(|(a, im)| a.len() == im.points.len())
        })
    }

    /// Total number of observed points.
    pub fn point_count(&self) -> usize {
        self.images.iter().map(|i| i.points.len()).sum()
    }
}

/// One measured point of the data: its image and its place in the image's
/// points (indices into [`CalibrationData::images`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DataPoint {
    /// The image's index.
    pub image: usize,
    /// The point's index in the image.
    pub point: usize,
    /// The measured point, mm.
    pub measured: Vector2<f64>,
}
