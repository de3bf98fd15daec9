//! The error type of the calibration crate.

use psdcal_model::ModelError;

use crate::data::DataPoint;
use thiserror::Error;

/// Everything that can make a calibration fail. Each message names the cause
/// and, where one exists, what the user can do about it.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum CalibError {
    /// Fewer usable images than the method needs.
    #[error("only {usable} usable image(s); calibration needs at least {needed} template poses")]
    TooFewImages {
        /// Images with enough points.
        usable: usize,
        /// Minimum required.
        needed: usize,
    },
    /// An image has too few points for a homography.
    #[error("image '{image}' has {points} point(s); a homography needs at least 4")]
    TooFewPoints {
        /// The image id.
        image: String,
        /// Its number of points.
        points: usize,
    },
    /// The data cannot determine the parameters (the reason says why).
    #[error("degenerate calibration data: {reason}")]
    Degenerate {
        /// What makes it degenerate and what to change.
        reason: String,
    },
    /// An LED index refers to no template LED.
    #[error("observation refers to LED index {led}, but the template has {template_len} LEDs")]
    UnknownLed {
        /// The index.
        led: usize,
        /// The template size.
        template_len: usize,
    },
    /// A numerical stage failed (the text says which and why).
    #[error("{stage} failed: {reason}")]
    Numerical {
        /// Which stage (homography, closed form, refinement, ...).
        stage: &'static str,
        /// Why.
        reason: String,
    },
    /// The refinement did not converge to a usable solution.
    #[error("refinement did not converge: {reason}")]
    NotConverged {
        /// Why (termination reason, last cost).
        reason: String,
    },
    /// The images contradict one LED's template position (a typo in its
    /// coordinates or its identifier); found when a calibration fails
    /// ([`crate::misplaced`]).
    #[error(
        "the images contradict template LED #{index} (index {led}): without it each image's \
         homography fits {score:.1} times better, in {images} images (without the next LED: \
         {next_score:.2} times); check its coordinates and identifier ({cause})"
    , index = led + 1)]
    MisplacedLed {
        /// Its index in the template.
        led: usize,
        /// Its score ([`crate::misplaced::MisplacedLed::score`]).
        score: f64,
        /// The next LED's score.
        next_score: f64,
        /// Images that scored it.
        images: usize,
        /// What the calibration said without this check.
        cause: String,
    },
    /// The sensor model could not be evaluated.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// An input is malformed (mismatched lengths, non-finite numbers, ...).
    #[error("invalid input: {reason}")]
    InvalidInput {
        /// What is wrong with it.
        reason: String,
    },
    /// The closed-form intrinsics (docs/model.md §4.4) give `f² ≤ 0`: the images
    /// do not determine the focal length linearly (nearly affine images,
    /// e.g. poses nearly parallel to the sensor or a long focal length, or
    /// uncorrected distortion).
    #[error(
        "closed-form intrinsics give f² = {f_squared:.3e} mm² (must be positive): the images do \
         not determine the focal length linearly (poses too close to parallel to the sensor, \
         or uncorrected distortion)"
    )]
    NonPositiveFocalSquared {
        /// The computed `f²`, mm².
        f_squared: f64,
    },
    /// The focal search ended at the edge of its interval with the error
    /// still falling past it: the focal length lies outside the interval
    /// searched (about `--focal-guess`, or 1–1000 mm without one).
    #[error(
        "the focal length lies outside the interval searched ({lo:.4}–{hi:.4} mm{}): the \
         template-plane error still falls from f = {f:.4} mm to f = {better_f:.4} mm ({cost:.4e} \
         → {better_cost:.4e} mm²)",
        match guess {
            Some(g) => format!(", about --focal-guess {g} mm"),
            None => String::new(),
        }
    )]
    FocalOutsideSearch {
        /// The focal guess the interval was centred on, mm.
        guess: Option<f64>,
        /// The interval searched, mm.
        lo: f64,
        /// Its upper end, mm.
        hi: f64,
        /// Where the search ended, mm.
        f: f64,
        /// The cost there, mm².
        cost: f64,
        /// A focal length past the interval with a lower cost, mm.
        better_f: f64,
        /// Its cost, mm².
        better_cost: f64,
    },
    /// Measured points outside the domain of the model's first stage (a
    /// PSD map is known only inside its scan's hull, docs/model.md §8.3).
    #[error(
        "{outside} of {points} data points lie outside the domain of the model's first stage \
         (first: image {}, point {}, at ({:.4}, {:.4}) mm)",
        first.image, first.point, first.measured.x, first.measured.y
    )]
    DataOutsideDomain {
        /// Points outside.
        outside: usize,
        /// Points of the data.
        points: usize,
        /// The first point outside.
        first: DataPoint,
    },
    /// The fitted correction folds over inside its own data: points lie
    /// outside the valid region (docs/model.md §8.2).
    #[error(
        "the distortion correction folds over inside its own data ({outside} of {points} \
         points lie outside its valid region, the nearest fold {fold_mm:.3} mm from the optical \
         centre)"
    )]
    DataOutsideValidRegion {
        /// Points outside.
        outside: usize,
        /// Points of the data.
        points: usize,
        /// Distance of the nearest fold from the optical centre, mm.
        fold_mm: f64,
        /// The first point outside.
        first: DataPoint,
        /// Its distance from the optical centre, mm.
        distance_mm: f64,
        /// Where the region ends in its direction, mm.
        limit_mm: f64,
    },
}
