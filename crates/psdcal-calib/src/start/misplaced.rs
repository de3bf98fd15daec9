//! Which LED contradicts the template: a typo in one LED's coordinates (or
//! its identifier) makes every image disagree with the template at that
//! LED, and the whole fit fails in ways that blame the poses. This check
//! runs only when a calibration fails, to name the LED instead.
//!
//! For every image with at least [`MIN_POINTS`] points, the homography of
//! all its points (DLT, docs/model.md §4.2) leaves an RMS transfer error
//! `e_all` (mm on the sensor), and the homography without point `k` leaves
//! `e₋ₖ` over the others. Removing a misplaced LED takes its typo out of the
//! fit, and the others then fit to the level of the noise and the lens
//! distortion; removing a correct LED changes little. So `s_k = e_all / e₋ₖ`
//! is large for a misplaced LED and near 1 for the others (measured: 5 to
//! 200 for a typo of 36–1 260 mm in one LED of the 14-LED template, at most
//! 1.6 for any correct LED, on noise-free and 40 dB data of both lenses).
//! An LED's score is the median of its `s_k` over the images that see it (at
//! least [`MIN_IMAGES_SEEN`]). The LED with the highest score is blamed when
//! its score is at least [`MIN_SCORE`] and at least [`MIN_SEPARATION`] times
//! the next LED's.

use nalgebra::Vector2;

use crate::data::CalibrationData;
use crate::start::homography::{fit_homography, HomographyOptions};

/// Fewest points of an image used by the check (one left out, six fitted:
/// a homography with residual degrees of freedom).
pub const MIN_POINTS: usize = 7;
/// Fewest images in which an LED must be seen to be scored.
pub const MIN_IMAGES_SEEN: usize = 3;
/// Smallest score that blames an LED.
pub const MIN_SCORE: f64 = 3.0;
/// The blamed LED's score over the next LED's, at least.
pub const MIN_SEPARATION: f64 = 2.0;

/// An LED whose template position the images contradict.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MisplacedLed {
    /// Its index in the template.
    pub led: usize,
    /// Its score: the median, over the images, of how many times the
    /// homography's RMS error shrinks without it.
    pub score: f64,
    /// The next LED's score.
    pub next_score: f64,
    /// Images that scored it.
    pub images: usize,
}

/// The LED the images contradict, if one stands out (module documentation).
pub fn misplaced_led(data: &CalibrationData) -> Option<MisplacedLed> {
    let options = HomographyOptions { normalize: true };
    let rms_of = |points: &mut dyn Iterator<Item = &crate::Observation>| -> Option<f64> {
        let (template, measured): (Vec<Vector2<f64>>, Vec<Vector2<f64>>) = points
            .map(|o| Some((*data.template.get(o.led)?, o.measured)))
            .collect::<Option<Vec<_>>>()?
            .into_iter()
            .unzip();
        fit_homography(&template, &measured, &options)
            .ok()
            .map(|fit| fit.rms)
            .filter(|rms| rms.is_finite())
    };
    let mut scores: Vec<Vec<f64>> = vec![Vec::new(); data.template.len()];
    for image in data
        .images
        .iter()
        .filter(|im| im.points.len() >= MIN_POINTS)
    {
        let Some(all) = rms_of(&mut image.points.iter()) else {
            continue;
        };
        for (k, point) in image.points.iter().enumerate() {
            let without = rms_of(
                &mut image
                    .points
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != k)
                    .map(|(_, o)| o),
            );
            if let Some(without) = without {
                scores[point.led].push(all / without.max(1e-300));
            }
        }
    }
    let mut ranked: Vec<(usize, f64, usize)> = scores
        .into_iter()
        .enumerate()
        .filter(|(_, s)| s.len() >= MIN_IMAGES_SEEN)
        .map(|(led, mut s)| {
            s.sort_by(f64::total_cmp);
            (led, s[s.len() / 2], s.len())
        })
        .collect();
    ranked.sort_by(|a, b| b.1.total_cmp(&a.1));
    let (&(led, score, images), next) = (ranked.first()?, ranked.get(1)?);
    (score >= MIN_SCORE && score >= MIN_SEPARATION * next.1).then_some(MisplacedLed {
        led,
        score,
        next_score: next.1,
        images,
    })
}
