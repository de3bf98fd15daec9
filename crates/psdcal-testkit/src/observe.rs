//! Synthetic observations: the points a template's LEDs produce on the
//! sensor in given poses, and Gaussian (or any) point noise.

use nalgebra::Vector2;
use psdcal_model::{Model, Pose, SensorModel};
use rand::distr::Distribution;
use rand::Rng;

/// Which point of an LED an observation holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointKind {
    /// The measured point: through the model's lens and PSD distortion
    /// (`Model::project_to_tolerance`).
    Measured,
    /// The ideal pinhole point (`Model::project_ideal`).
    Ideal,
}

/// The point of every LED of `template` in every pose: `points[image][led]`,
/// mm, sensor frame, noise-free. Panics when a point cannot be projected
/// (the poses are meant to be drawn so that every LED is seen).
pub fn image_points(
    model: &SensorModel,
    template: &[Vector2<f64>],
    poses: &[Pose],
    kind: PointKind,
) -> Vec<Vec<Vector2<f64>>> {
    let model = Model::standard(model);
    poses
        .iter()
        .map(|pose| {
            template
                .iter()
                .map(|p| match kind {
                    PointKind::Measured => {
                        model.project_to_tolerance(pose, p).expect("projectable")
                    }
                    PointKind::Ideal => model.project_ideal(pose, p).expect("in front"),
                })
                .collect()
        })
        .collect()
}

/// Adds to every point a draw of `noise` for x, then one for y, image by
/// image and LED by LED, from `rng`.
pub fn add_noise<D, R>(points: &mut [Vec<Vector2<f64>>], noise: &D, rng: &mut R)
where
    D: Distribution<f64>,
    R: Rng + ?Sized,
{
    for image in points.iter_mut() {
        for m in image.iter_mut() {
            let dx = noise.sample(rng);
            let dy = noise.sample(rng);
            *m += Vector2::new(dx, dy);
        }
    }
}
