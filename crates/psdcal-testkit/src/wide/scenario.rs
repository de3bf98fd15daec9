//! [`WideScenario`]: one wide scenario drawn from its index.

use nalgebra::Vector2;
use psdcal_model::paper_setup::scatter14;
use psdcal_model::{Pose, SensorModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use super::noise::{draw_sigma, snr_db_equivalent};
use super::poses::{draw_region, draw_view, AimRegion, WideView};
use super::sensor::{draw_sensor, Lens};
use super::WIDE_SEED_BASE;

/// One image: its pose and the LEDs it keeps.
#[derive(Debug, Clone, PartialEq)]
pub struct WideImage {
    /// The pose and how it was drawn.
    pub view: WideView,
    /// `(led, measured point)`, mm, noise included, in LED order.
    pub points: Vec<(usize, Vector2<f64>)>,
}

/// A wide scenario (the module documentation of [`crate::wide`]).
#[derive(Debug, Clone, PartialEq)]
pub struct WideScenario {
    /// Its index: the stream is seeded with [`WIDE_SEED_BASE`]` + index`.
    pub index: u64,
    /// The lens it is built around.
    pub lens: Lens,
    /// The true sensor.
    pub truth: SensorModel,
    /// The template's scale factor on `scatter14`.
    pub template_scale: f64,
    /// The LEDs, mm (`scatter14` × `template_scale`).
    pub template: Vec<Vector2<f64>>,
    /// Where the images are aimed.
    pub region: AimRegion,
    /// The point noise σ per coordinate, mm (0: noise-free).
    pub sigma_mm: f64,
    /// The images.
    pub images: Vec<WideImage>,
}

impl WideScenario {
    /// Scenario `index`, drawn in the order of the module documentation:
    /// sensor, template scale (log-uniform in 0.5–2), number of images
    /// (uniform in 9–20), aim region, σ, then each image's view, then the
    /// noise (image by image, LED by LED, x then y).
    pub fn draw(index: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(WIDE_SEED_BASE + index);
        let (lens, truth) = draw_sensor(&mut rng);
        let template_scale = rng.random_range(0.5f64.ln()..2f64.ln()).exp();
        let template: Vec<_> = scatter14().iter().map(|p| p * template_scale).collect();
        let n_images = rng.random_range(9..=20usize);
        let region = draw_region(&mut rng);
        let sigma_mm = draw_sigma(&mut rng);
        let mut images: Vec<WideImage> = (0..n_images)
            .map(|_| {
                let (view, points) = draw_view(&truth, &template, &region, &mut rng);
                WideImage { view, points }
            })
            .collect();
        if sigma_mm > 0.0 {
            for image in &mut images {
                for (_, m) in &mut image.points {
                    let dx = sigma_mm * rng.sample::<f64, _>(StandardNormal);
                    let dy = sigma_mm * rng.sample::<f64, _>(StandardNormal);
                    *m += Vector2::new(dx, dy);
                }
            }
        }
        Self {
            index,
            lens,
            truth,
            template_scale,
            template,
            region,
            sigma_mm,
            images,
        }
    }

    /// The true pose of every image.
    pub fn poses(&self) -> Vec<Pose> {
        self.images.iter().map(|i| i.view.pose).collect()
    }

    /// Whether the PSD is distorted (`l1 ≠ 0`).
    pub fn has_psd_distortion(&self) -> bool {
        self.truth.distortion.l1 != 0.0
    }

    /// The SNR σ stands for, dB ([`snr_db_equivalent`]).
    pub fn snr_db(&self) -> f64 {
        snr_db_equivalent(self.sigma_mm)
    }

    /// Total number of points kept.
    pub fn point_count(&self) -> usize {
        self.images.iter().map(|i| i.points.len()).sum()
    }

    /// The mean number of LEDs an image keeps, of the template's.
    pub fn kept_fraction(&self) -> f64 {
        self.point_count() as f64 / (self.images.len() * self.template.len()) as f64
    }
}
