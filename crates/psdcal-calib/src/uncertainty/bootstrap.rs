//! A resampling estimate of the covariance (docs/model.md §4.6, "The
//! bootstrap"): the case bootstrap by image. Each resample draws as many
//! images as the data set has, with replacement (redrawn until it holds at
//! least [`MIN_DISTINCT_IMAGES`] distinct images), refits them from the
//! full-data solution (model and the drawn images' poses; a warm start, so
//! a refit takes a few iterations), and the covariance is the sample
//! covariance of the resampled estimates of the freed parameters.
//!
//! Resample `b` draws its images from `ChaCha8Rng::seed_from_u64(seed + b)`;
//! the refits run in parallel (rayon) and are gathered in resample order, so
//! the covariance is the same whatever the number of threads. A refit that
//! fails or does not converge is left out (counted in
//! [`BootstrapReport::failed`]); more than a tenth failing is an error.
//!
//! Unlike `σ² (JᵀJ)⁻¹` it needs no assumption on the noise (each image's
//! points keep their own noise, correlations within an image included) and
//! follows the cost's non-linearity; it does not remove the estimate's bias.
//! Its own sampling error: the relative standard deviation of a σ from `N`
//! resamples is about `1/√(2N)` (7 % for N = 100).

use nalgebra::DMatrix;
use psdcal_model::ParameterCovariance;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use crate::data::{CalibrationData, ImageObservations};
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::refine::solve::refine;
use crate::uncertainty::covariance::{correlation_warnings, Covariance, CovarianceMethod};
use crate::warning::FitWarning;
use crate::CalibError;

/// The fewest distinct images a resample holds.
pub const MIN_DISTINCT_IMAGES: usize = 3;

/// The fewest resamples accepted.
pub const MIN_RESAMPLES: usize = 10;

/// Options of [`bootstrap_covariance`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct BootstrapOptions {
    /// Number of resamples (at least [`MIN_RESAMPLES`]).
    pub resamples: usize,
    /// Base seed: resample `b` draws from `ChaCha8Rng::seed_from_u64(seed + b)`.
    pub seed: u64,
}

/// What the bootstrap did.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct BootstrapReport {
    /// Resamples asked for.
    pub resamples: usize,
    /// Resamples whose refit failed or did not converge (left out).
    pub failed: usize,
}

/// The images of resample `b`: indices into the data set's images.
pub fn resample_images(images: usize, seed: u64, b: usize) -> Vec<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_add(b as u64));
    let need = MIN_DISTINCT_IMAGES.min(images);
    loop {
        let drawn: Vec<usize> = (0..images).map(|_| rng.random_range(0..images)).collect();
        let mut distinct = drawn.clone();
        distinct.sort_unstable();
        distinct.dedup();
        if distinct.len() >= need {
            return drawn;
        }
    }
}

/// The data set of the images `drawn` (a repeated image gets a distinct id).
fn resampled(data: &CalibrationData, drawn: &[usize]) -> CalibrationData {
    let images = drawn
        .iter()
        .enumerate()
        .map(|(n, &i)| ImageObservations {
            id: format!("{}#{n}", data.images[i].id),
            points: data.images[i].points.clone(),
        })
        .collect();
    CalibrationData {
        template: data.template.clone(),
        lines: data.lines.clone(),
        images,
        geometry: data.geometry,
        amplitudes: data
            .amplitudes
            .as_ref()
            .map(|a| drawn.iter().map(|&i| a[i].clone()).collect()),
        noise_scale: data
            .noise_scale
            .as_ref()
            .map(|s| drawn.iter().map(|&i| s[i].clone()).collect()),
    }
}

/// The bootstrap covariance around `refined` (the full-data solution), with
/// `analytic` (its linear or sandwich covariance) supplying the pose blocks,
/// σ², degrees of freedom and identifiability warnings.
pub fn bootstrap_covariance(
    data: &CalibrationData,
    refined: &Refined,
    options: &RefineOptions,
    analytic: &Covariance,
    boot: &BootstrapOptions,
) -> Result<(Covariance, BootstrapReport), CalibError> {
    if boot.resamples < MIN_RESAMPLES {
        return Err(CalibError::InvalidInput {
            reason: format!(
                "the bootstrap needs at least {MIN_RESAMPLES} resamples, not {}",
                boot.resamples
            ),
        });
    }
    let names = options.free_names();
    let estimates: Vec<Option<Vec<f64>>> = (0..boot.resamples)
        .into_par_iter()
        .map(|b| {
            let drawn = resample_images(data.images.len(), boot.seed, b);
            let d = resampled(data, &drawn);
            let poses: Vec<_> = drawn.iter().map(|&i| refined.poses[i]).collect();
            let r = refine(&d, refined.model.clone(), &poses, options).ok()?;
            r.report.termination.converged().then(|| {
                names
                    .iter()
                    .map(|n| r.model.get(n).unwrap_or(f64::NAN))
                    .collect()
            })
        })
        .collect();
    let kept: Vec<&Vec<f64>> = estimates
        .iter()
        .flatten()
        .filter(|e| e.iter().all(|v| v.is_finite()))
        .collect();
    let failed = boot.resamples - kept.len();
    if failed * 10 > boot.resamples {
        return Err(CalibError::NotConverged {
            reason: format!(
                "{failed} of {} bootstrap refits failed: the resampled images do not determine the parameters; \
                 use --uncertainty linear or add images",
                boot.resamples
            ),
        });
    }
    let p = names.len();
    let n = kept.len() as f64;
    let mean: Vec<f64> = (0..p)
        .map(|k| kept.iter().map(|e| e[k]).sum::<f64>() / n)
        .collect();
    let matrix = DMatrix::from_fn(p, p, |i, j| {
        kept.iter()
            .map(|e| (e[i] - mean[i]) * (e[j] - mean[j]))
            .sum::<f64>()
            / (n - 1.0)
    });
    let parameters =
        ParameterCovariance::new(names, matrix).map_err(|e| CalibError::Numerical {
            stage: "bootstrap covariance",
            reason: e.to_string(),
        })?;
    let mut warnings: Vec<FitWarning> = analytic
        .warnings
        .iter()
        .filter(|w| !matches!(w, FitWarning::StronglyCorrelated { .. }))
        .cloned()
        .collect();
    warnings.extend(correlation_warnings(&parameters));
    let covariance = Covariance {
        parameters,
        pose_blocks: analytic.pose_blocks.clone(),
        sigma2: analytic.sigma2,
        dof: analytic.dof,
        warnings,
        method: CovarianceMethod::Bootstrap {
            resamples: boot.resamples,
            seed: boot.seed,
        },
    };
    Ok((
        covariance,
        BootstrapReport {
            resamples: boot.resamples,
            failed,
        },
    ))
}
