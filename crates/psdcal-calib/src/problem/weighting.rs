//! Noise weighting of the refinement: each point's residual is whitened by
//! the covariance its electrode noise gives it, so that the refinement is the
//! maximum-likelihood estimate under the chosen noise model instead of the
//! paper's unweighted least squares (P29).
//!
//! The impact point of the pin-cushion PSD (docs/model.md §1) is
//! `x = (Lx/2) N_x / S`, `y = (Ly/2) N_y / S` over the gain-corrected
//! amplitudes `w_k = V_k / g_k`, `S = Σ w_k`, `N_x = Σ sx_k w_k`,
//! `N_y = Σ sy_k w_k` (signs `sx, sy = ±1` of the electrode corners). Its
//! derivative with respect to one channel is
//!
//! ```text
//! ∂(x, y)/∂w_k = d_k / S,   d_k = ((Lx/2)(sx_k − u), (Ly/2)(sy_k − v)),   u = 2x/Lx, v = 2y/Ly
//! ```
//!
//! so independent channel noise of standard deviation `σ_k` gives the point
//! the covariance
//!
//! ```text
//! C_m = Σ_k (σ_k / S)² d_k d_kᵀ                                   (sensor frame, mm²)
//! ```
//!
//! Noise models ([`NoiseModel`]):
//! - `Uniform`: every coordinate equally noisy and independent, `C_m = I`
//!   (the paper's cost, the default);
//! - `ChannelSnr`: the same SNR on every channel, `σ_k ∝ w_k` (the paper's
//!   simulated noise, docs/model.md §6): `C_m ∝ Σ_k q_k² d_k d_kᵀ` with the
//!   channel fractions `q_k = w_k / S` — from the amplitudes when the data
//!   carry them, else from the forward model at the point
//!   (`psdcal_model::psd::electrode_currents`, `q = (1±u)(1±v)/4`). Points near the electrodes are far less noisy
//!   than points at the centre (at `u = v = 0.9`, a quarter of the centre's
//!   standard deviation);
//!   With a per-record SNR ([`CalibrationData::noise_scale`], `10^(−SNR/10)`
//!   from signals.csv's `snr_db`) each point's `C_m` is multiplied by its
//!   record's scale;
//! - `ChannelFloor`: the same absolute noise on every channel (an amplifier
//!   or thermal floor), `σ_k = σ`: `C_m ∝ Σ_k d_k d_kᵀ / S²`, brighter
//!   spots (larger `S`) weigh more; without amplitudes every spot counts as
//!   equally bright.
//!
//! A floor of [`COVARIANCE_FLOOR`] times the centre's variance is added to
//! `C_m` (no real channel is noiseless; it keeps a point at an electrode from
//! taking infinite weight).
//!
//! Each residual is then whitened: with `C` its covariance in the cost's
//! plane — `C_m` for the image-plane cost, `J C_m Jᵀ` with
//! `J = ∂back_project/∂m` for the template-plane cost — and `C = R Rᵀ`
//! (Cholesky), the weighted residual is `R⁻¹ r`, whose squared norm is
//! `rᵀ C⁻¹ r`. The covariances are scaled so that their mean half-trace is
//! 1: the weighted cost stays in the cost's units (mm² on the template or
//! the sensor) and close to the unweighted one in size. Because `J` depends
//! on the parameters, the template-plane weights are recomputed at each
//! solution and the refinement repeated until the weighted cost settles
//! ([`mod@crate::refine`]).

use nalgebra::{Matrix2, Vector2};
use psdcal_model::psd::{electrode_currents, impact_point_amplitude_jacobian};
use psdcal_model::{Amplitudes, ChannelGains, Model, Pose, PsdGeometry};
use serde::Serialize;

use crate::data::CalibrationData;
use crate::CalibError;
use psdcal_model::CostKind;

/// Floor added to a point's covariance, relative to the variance of a point
/// at the sensor's centre under the same model.
pub const COVARIANCE_FLOOR: f64 = 1e-4;

/// How the electrode noise is distributed (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum NoiseModel {
    /// Unweighted least squares (the paper's cost).
    #[default]
    Uniform,
    /// The same SNR on every channel: noise proportional to each channel's
    /// amplitude.
    ChannelSnr,
    /// The same absolute noise on every channel.
    ChannelFloor,
}

impl NoiseModel {
    /// Every noise model, in the order the command line lists them.
    pub const ALL: [NoiseModel; 3] = [
        NoiseModel::Uniform,
        NoiseModel::ChannelSnr,
        NoiseModel::ChannelFloor,
    ];

    /// The name used on the command line and in reports.
    pub fn name(&self) -> &'static str {
        match self {
            NoiseModel::Uniform => "uniform",
            NoiseModel::ChannelSnr => "channel-snr",
            NoiseModel::ChannelFloor => "channel-floor",
        }
    }
}

impl std::str::FromStr for NoiseModel {
    type Err = String;

    /// `uniform`, `channel-snr` or `channel-floor` (any case, `_` for `-`).
    fn from_str(text: &str) -> Result<Self, String> {
        let wanted = text.trim().to_ascii_lowercase().replace('_', "-");
        Self::ALL
            .into_iter()
            .find(|n| n.name() == wanted)
            .ok_or_else(|| {
                format!("expected uniform, channel-snr or channel-floor, found '{text}'")
            })
    }
}

#[cfg(feature = "clap")]
impl clap::ValueEnum for NoiseModel {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

/// The covariance shape `Σ_k σ_k² (∂m/∂V_k)(∂m/∂V_k)ᵀ` (mm², up to the
/// common noise scale) of an impact point `point` on `geometry`, under
/// `noise`, with the gain-corrected amplitudes behind it when known (else
/// the forward model's, of unit total). Includes the floor.
pub fn point_covariance(
    noise: NoiseModel,
    geometry: &PsdGeometry,
    point: &Vector2<f64>,
    corrected_amplitudes: Option<&Amplitudes>,
) -> Matrix2<f64> {
    if noise == NoiseModel::Uniform {
        return Matrix2::identity();
    }
    let amps = corrected_amplitudes
        .copied()
        .unwrap_or_else(|| electrode_currents(geometry, point, 1.0));
    // The floor's reference: a spot of the same total at the centre.
    let centre = electrode_currents(geometry, &Vector2::zeros(), amps.total());
    let floor = 0.5 * channel_noise_covariance(noise, geometry, &centre).trace();
    channel_noise_covariance(noise, geometry, &amps)
        + Matrix2::identity() * (COVARIANCE_FLOOR * floor)
}

/// `Σ_k σ_k² (∂m/∂V_k)(∂m/∂V_k)ᵀ` with `σ_k = V_k` (channel SNR) or 1
/// (channel floor); zero where the amplitudes give no point.
fn channel_noise_covariance(
    noise: NoiseModel,
    geometry: &PsdGeometry,
    amps: &Amplitudes,
) -> Matrix2<f64> {
    let Ok((_, jac)) = impact_point_amplitude_jacobian(geometry, amps) else {
        return Matrix2::zeros();
    };
    let sigma = match noise {
        NoiseModel::ChannelSnr => [amps.vx1, amps.vx2, amps.vy1, amps.vy2],
        _ => [1.0; 4],
    };
    let mut c = Matrix2::zeros();
    for (k, sigma_k) in sigma.iter().enumerate() {
        let d = jac.column(k);
        c += d * d.transpose() * (sigma_k * sigma_k);
    }
    c
}

/// The whitening matrix of every point (`[image][point]`, same order as the
/// data): the weighted residual is `whiten · r`.
#[derive(Debug, Clone, PartialEq)]
pub struct PointWeights {
    /// Per image, per point, `R⁻¹` with `R Rᵀ` the residual's covariance.
    pub whiten: Vec<Vec<Matrix2<f64>>>,
}

impl PointWeights {
    /// The weights of `data` under `noise` for the residuals of `cost` at
    /// `(model, gains, poses)` (`gains` when the points are recomputed from
    /// the amplitudes). `None` for the uniform model (no weighting).
    pub fn compute(
        data: &CalibrationData,
        noise: NoiseModel,
        cost: CostKind,
        model: &Model,
        poses: &[Pose],
    ) -> Result<Option<Self>, CalibError> {
        if noise == NoiseModel::Uniform {
            return Ok(None);
        }
        let mut covariances: Vec<Vec<Matrix2<f64>>> = Vec::with_capacity(data.images.len());
        let mut trace_sum = 0.0;
        for (i, image) in data.images.iter().enumerate() {
            let mut row = Vec::with_capacity(image.points.len());
            let rotation = poses[i].rotation_jacobian();
            let mut jac = model.jacobian_buffer();
            for (k, obs) in image.points.iter().enumerate() {
                let numerical = |e: psdcal_model::ModelError| CalibError::Numerical {
                    stage: "noise weighting",
                    reason: format!("image '{}', LED #{}: {e}", image.id, obs.led + 1),
                };
                let m = match (model.gains(), data.amplitudes.as_ref()) {
                    (Some(_), Some(a)) => model
                        .measured_from_amplitudes(&a[i][k])
                        .map_err(numerical)?,
                    _ => obs.measured,
                };
                let corrected = data
                    .amplitudes
                    .as_ref()
                    .map(|a| a[i][k].divide_gains(&model.gains().unwrap_or(ChannelGains::UNIT)));
                let scale = match (noise, data.noise_scale.as_ref()) {
                    (NoiseModel::ChannelSnr, Some(s)) => s[i][k],
                    _ => 1.0,
                };
                let c_m = point_covariance(noise, &data.geometry, &m, corrected.as_ref()) * scale;
                let c = match cost {
                    CostKind::Image => c_m,
                    CostKind::Template => {
                        let (_, j) = model
                            .back_project_with_jacobians(&poses[i], &rotation, &m, &mut jac)
                            .map_err(numerical)?;
                        j.wrt_point * c_m * j.wrt_point.transpose()
                    }
                };
                trace_sum += 0.5 * c.trace();
                row.push(c);
            }
            covariances.push(row);
        }
        let mean = trace_sum / data.point_count().max(1) as f64;
        if !(mean.is_finite() && mean > 0.0) {
            return Err(CalibError::Numerical {
                stage: "noise weighting",
                reason: format!("mean point variance {mean:e}"),
            });
        }
        let mut whiten = Vec::with_capacity(covariances.len());
        for (image, row) in data.images.iter().zip(covariances) {
            let mut out = Vec::with_capacity(row.len());
            for (obs, c) in image.points.iter().zip(row) {
                let r = (c / mean).cholesky().ok_or_else(|| CalibError::Numerical {
                    stage: "noise weighting",
                    reason: format!(
                        "image '{}', LED #{}: the point's covariance is not positive definite",
                        image.id,
                        obs.led + 1
                    ),
                })?;
                let l = r.l();
                let inv = l.try_inverse().ok_or_else(|| CalibError::Numerical {
                    stage: "noise weighting",
                    reason: format!(
                        "image '{}', LED #{}: singular covariance",
                        image.id,
                        obs.led + 1
                    ),
                })?;
                out.push(inv);
            }
            whiten.push(out);
        }
        Ok(Some(Self { whiten }))
    }

    /// Whitening matrix of point `k` of image `i`.
    pub fn get(&self, i: usize, k: usize) -> &Matrix2<f64> {
        &self.whiten[i][k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use psdcal_model::psd::{electrode_currents, impact_point};

    /// The covariance of the point computed from amplitudes with independent
    /// channel noise, by Monte Carlo-free linear propagation through central
    /// differences of the impact-point formula.
    fn propagated(geometry: &PsdGeometry, a: &Amplitudes, sigma: [f64; 4]) -> Matrix2<f64> {
        let mut c = Matrix2::zeros();
        for (k, sigma_k) in sigma.iter().enumerate() {
            let h = 1e-6 * a.total();
            let bump = |s: f64| {
                let mut b = *a;
                match k {
                    0 => b.vx1 += s,
                    1 => b.vx2 += s,
                    2 => b.vy1 += s,
                    _ => b.vy2 += s,
                }
                impact_point(geometry, &b).unwrap()
            };
            let d = (bump(h) - bump(-h)) / (2.0 * h);
            c += d * d.transpose() * (sigma_k * sigma_k);
        }
        c
    }

    #[test]
    fn covariance_matches_finite_difference_propagation() {
        let geometry = PsdGeometry { lx: 9.0, ly: 7.0 };
        for (x, y) in [(0.0, 0.0), (1.3, -2.1), (-3.9, 3.0), (4.0, 3.2)] {
            let p = Vector2::new(x, y);
            let a = electrode_currents(&geometry, &p, 2.5);
            let snr = [a.vx1, a.vx2, a.vy1, a.vy2];
            let expected = propagated(&geometry, &a, snr);
            for amps in [Some(&a), None] {
                let c = point_covariance(NoiseModel::ChannelSnr, &geometry, &p, amps);
                let floor = c - expected;
                // Only the documented floor separates the two.
                let centre = 0.25 * 0.5 * (4.5f64.powi(2) + 3.5f64.powi(2));
                assert!(
                    (floor - Matrix2::identity() * COVARIANCE_FLOOR * centre).norm() < 1e-9,
                    "({x}, {y}) {amps:?}: {c} vs {expected}"
                );
            }
            let expected = propagated(&geometry, &a, [1.0; 4]);
            let c = point_covariance(NoiseModel::ChannelFloor, &geometry, &p, Some(&a));
            let centre = 4.0 / a.total().powi(2) * 0.5 * (4.5f64.powi(2) + 3.5f64.powi(2));
            assert!(
                (c - expected - Matrix2::identity() * COVARIANCE_FLOOR * centre).norm()
                    < 1e-9 * expected.norm(),
                "floor model at ({x}, {y})"
            );
        }
    }

    #[test]
    fn points_near_the_electrodes_are_quieter_under_channel_snr() {
        let geometry = PsdGeometry::default();
        let centre = point_covariance(NoiseModel::ChannelSnr, &geometry, &Vector2::zeros(), None);
        let corner = point_covariance(
            NoiseModel::ChannelSnr,
            &geometry,
            &Vector2::new(4.05, 4.05),
            None,
        );
        // Centre: four channels of q = 1/4 and |d_x| = h: h²/4 per coordinate.
        assert!((centre[(0, 0)] / (1.0 + COVARIANCE_FLOOR) - 4.5f64.powi(2) / 4.0).abs() < 1e-9);
        let ratio = (corner[(0, 0)] / centre[(0, 0)]).sqrt();
        assert!(ratio > 0.2 && ratio < 0.3, "std ratio {ratio}");
    }

    /// A per-record SNR scales each point's covariance by `10^(−SNR/10)`:
    /// two copies of the same image, the second 6.0206 dB noisier (four
    /// times the variance), get whitening matrices exactly half as large
    /// (`chol(4 C) = 2 chol(C)`), under channel-snr only.
    #[test]
    fn a_per_record_snr_scales_the_weights() {
        use crate::{ImageObservations, Observation};
        use psdcal_model::{Model, Pose, SensorModel};
        let truth = SensorModel::paper_lens2();
        let pose = Pose::new(
            nalgebra::Vector3::new(0.1, -0.2, 0.05),
            nalgebra::Vector3::new(10.0, -20.0, 1200.0),
        );
        let template: Vec<Vector2<f64>> =
            [(-100.0, -80.0), (90.0, -60.0), (0.0, 70.0), (60.0, 40.0)]
                .iter()
                .map(|&(x, y)| Vector2::new(x, y))
                .collect();
        let points: Vec<Observation> = template
            .iter()
            .enumerate()
            .map(|(led, p)| Observation {
                led,
                measured: Model::standard(&truth)
                    .project_to_tolerance(&pose, p)
                    .unwrap(),
            })
            .collect();
        let image = |id: &str| ImageObservations {
            id: id.into(),
            points: points.clone(),
        };
        let mut data = CalibrationData {
            template,
            lines: Vec::new(),
            images: vec![image("quiet"), image("noisy")],
            geometry: PsdGeometry::default(),
            amplitudes: None,
            noise_scale: None,
        };
        data.noise_scale = Some(vec![vec![1.0; 4], vec![4.0; 4]]);
        let model = Model::standard(&truth);
        for cost in [CostKind::Image, CostKind::Template] {
            let w =
                PointWeights::compute(&data, NoiseModel::ChannelSnr, cost, &model, &[pose, pose])
                    .unwrap()
                    .unwrap();
            for k in 0..4 {
                let ratio = w.get(1, k).component_div(w.get(0, k));
                for v in ratio.iter().filter(|v| v.is_finite()) {
                    assert!((v - 0.5).abs() < 1e-12, "{cost:?}, point {k}: {ratio}");
                }
            }
            // The floor model ignores the scales.
            let f =
                PointWeights::compute(&data, NoiseModel::ChannelFloor, cost, &model, &[pose, pose])
                    .unwrap()
                    .unwrap();
            for k in 0..4 {
                assert!((f.get(1, k) - f.get(0, k)).norm() < 1e-12 * f.get(0, k).norm());
            }
        }
        data.noise_scale = Some(vec![vec![1.0; 4], vec![0.0; 4]]);
        assert!(data.check().is_err());
    }
}
