//! Electrical calibration of the channel gains (the paper's route, docs/model.md
//! §1): from records in which all four channels carry the same current — a
//! test current injected into every channel, or a light spot centred on a
//! symmetric PSD — each amplitude ratio `V_k / V_x1` measures the relative
//! gain `g_k = K_k / K_x1` directly.
//!
//! With `n` such records, `ĝ_k` is the mean of the ratios and its standard
//! deviation the sample standard deviation of the ratios over `√n` (the
//! records' noise is independent).

use psdcal_model::{Amplitudes, ChannelGains};
use serde::Serialize;

use crate::CalibError;

/// Relative gains estimated from equal-current records.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GainEstimate {
    /// The gains.
    pub gains: ChannelGains,
    /// Standard deviation of `(g_x2, g_y1, g_y2)`.
    pub std: [f64; 3],
    /// Records used.
    pub records: usize,
}

/// Estimates the relative gains from records in which all four channels
/// carry the same current. At least two records with positive, finite
/// amplitudes are needed.
pub fn equal_current_gains(records: &[Amplitudes]) -> Result<GainEstimate, CalibError> {
    if records.len() < 2 {
        return Err(CalibError::InvalidInput {
            reason: format!(
                "{} equal-current record(s); at least 2 are needed to estimate the gains and their spread",
                records.len()
            ),
        });
    }
    let mut ratios: [Vec<f64>; 3] = Default::default();
    for (k, a) in records.iter().enumerate() {
        let values = [a.vx1, a.vx2, a.vy1, a.vy2];
        if values.iter().any(|v| !v.is_finite() || *v <= 0.0) {
            return Err(CalibError::InvalidInput {
                reason: format!(
                    "equal-current record #{} has a zero, negative or non-finite amplitude",
                    k + 1
                ),
            });
        }
        ratios[0].push(a.vx2 / a.vx1);
        ratios[1].push(a.vy1 / a.vx1);
        ratios[2].push(a.vy2 / a.vx1);
    }
    let n = records.len() as f64;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / n;
    let sd = |v: &[f64]| {
        let m = mean(v);
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() / n.sqrt()
    };
    let gains = ChannelGains {
        x2: mean(&ratios[0]),
        y1: mean(&ratios[1]),
        y2: mean(&ratios[2]),
    };
    gains.validate()?;
    Ok(GainEstimate {
        gains,
        std: [sd(&ratios[0]), sd(&ratios[1]), sd(&ratios[2])],
        records: records.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn recovers_the_gains_with_an_honest_sigma() {
        let truth = ChannelGains {
            x2: 1.07,
            y1: 0.95,
            y2: 1.02,
        };
        let noise = Normal::new(0.0, 1e-3).unwrap();
        // Over many repetitions the spread of ĝ matches the reported σ.
        let (mut estimates, mut reported) = (Vec::new(), Vec::new());
        for seed in 0..300 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let records: Vec<Amplitudes> = (0..20)
                .map(|_| Amplitudes {
                    vx1: 1.0 + noise.sample(&mut rng),
                    vx2: truth.x2 + noise.sample(&mut rng),
                    vy1: truth.y1 + noise.sample(&mut rng),
                    vy2: truth.y2 + noise.sample(&mut rng),
                })
                .collect();
            let e = equal_current_gains(&records).unwrap();
            estimates.push(e.gains.x2);
            reported.push(e.std[0]);
        }
        let n = estimates.len() as f64;
        let mean = estimates.iter().sum::<f64>() / n;
        let spread = (estimates.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let sigma = reported.iter().sum::<f64>() / n;
        // 300 repetitions: the spread scatters by about 4 %; allow 15 %.
        assert!(
            (spread / sigma - 1.0).abs() < 0.15,
            "spread {spread:e} vs σ {sigma:e}"
        );
        assert!((mean - truth.x2).abs() < 4.0 * spread / n.sqrt());
        // Clean records give the gains exactly.
        let clean = vec![
            Amplitudes {
                vx1: 2.0,
                vx2: 2.0 * 1.07,
                vy1: 2.0 * 0.95,
                vy2: 2.0 * 1.02
            };
            3
        ];
        let e = equal_current_gains(&clean).unwrap();
        assert!((e.gains.x2 - 1.07).abs() < 1e-15 && e.std[0] < 1e-15);
        // Refusals.
        assert!(equal_current_gains(&clean[..1]).is_err());
        let bad = vec![
            Amplitudes {
                vx1: 0.0,
                vx2: 1.0,
                vy1: 1.0,
                vy2: 1.0
            };
            2
        ];
        assert!(equal_current_gains(&bad).is_err());
    }
}
