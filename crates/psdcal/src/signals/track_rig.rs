//! `track --rig`: positions per window and LED from every sensor's stream
//! (docs/model.md §5, §8.5; docs/formats.md "Raw recordings").
//!
//! The rig's S sensors are sampled together: one stream of `4 S` channels,
//! sensor after sensor in rig.json's order (or named `SENSOR/vx1` …). Each
//! window is demodulated per sensor on its own, exactly as one sensor's
//! `track` does. Per LED, every sensor whose window is demodulated and not
//! dark gives a ray: its angle of arrival with the ray covariance
//! `Σ_ab = Σ_calibration + σ_m² J_m J_mᵀ`, the point noise `σ_m` from the
//! window's own amplitude noise: `Σ_m = J_V diag(σ_V²) J_Vᵀ` through the
//! impact point's amplitude Jacobian (docs/model.md §1), taken isotropic,
//! `σ_m² = tr(Σ_m) / 2`. Two rays or more are triangulated (psdcal-locate's
//! weighted least squares, covariance by the sandwich). Row:
//! `t_s,led,sensors,x_world_mm,y_world_mm,z_world_mm,sigma_x_world_mm,
//! sigma_y_world_mm,sigma_z_world_mm,cov_xy_world_mm2,cov_xz_world_mm2,
//! cov_yz_world_mm2,sigma_position_mm,snr_db,status` — `sensors` the rays'
//! sensors (`;`-separated), `snr_db` the lowest of theirs, `status` `ok`, a
//! caution (e.g. `nearly_parallel_rays`), or why no position
//! (`too_few_sensors` when fewer than two sensors see the LED).
//!
//! With a tracking filter (`--filter cv`, psdcal-locate's `track_filter`)
//! each LED's intersection (with its covariance) updates its
//! constant-velocity Kalman filter at the window's `t_s`; the row then holds
//! the filtered position and covariance, its `status` is the intersection's
//! (`gated` for an outlier and `predicted` for a window without a fix, both
//! answered by the prediction), and three columns follow `status`:
//! `vx_mm_s,vy_mm_s,vz_mm_s`, the filtered velocity (empty without a track).

use std::path::Path;

use nalgebra::{Matrix3, Vector3};
use psdcal_io::Tones;
use psdcal_locate::{
    status_of, triangulate, CvFilter, FilterStep, LocateOptions, Measurement, Rig, TrackFilter,
    WorldRay,
};
use psdcal_model::psd::impact_point_amplitude_jacobian;
use psdcal_model::Amplitudes;
use psdcal_signal::{RecordEstimate, SignalError};

use crate::answer::locate::{covariance_fields, load_rig};
use crate::base::error::Result;
use crate::base::table::num;

/// The rig's header.
pub(crate) const HEADER: &str = "t_s,led,sensors,x_world_mm,y_world_mm,z_world_mm,\
sigma_x_world_mm,sigma_y_world_mm,sigma_z_world_mm,cov_xy_world_mm2,cov_xz_world_mm2,\
cov_yz_world_mm2,sigma_position_mm,snr_db,status";

/// The filter's extra columns.
pub(crate) const VELOCITY_HEADER: &str = ",vx_mm_s,vy_mm_s,vz_mm_s";

/// One LED's answer in one window.
#[derive(Debug, Clone, PartialEq)]
pub struct LedFix {
    /// The LED (tones.csv's name).
    pub led: String,
    /// The sensors whose rays made the position.
    pub sensors: Vec<String>,
    /// The position and its covariance, world frame, mm and mm².
    pub position: Option<(Vector3<f64>, Matrix3<f64>)>,
    /// The filtered velocity, mm/s (with a filter and a track).
    pub velocity: Option<Vector3<f64>>,
    /// The lowest SNR of the rays' sensors, dB.
    pub snr_db: Option<f64>,
    /// `ok`, a caution, or why there is no position.
    pub status: String,
    /// Per sensor of the rig (its order): the lowest channel SNR of this
    /// LED, dB, and its status (`ok`, `dark`, or why no ray).
    pub per_sensor: Vec<(Option<f64>, String)>,
}

/// A rig ready to track.
pub(crate) struct TrackRig {
    rig: Rig,
}

/// The filters of a rig's LEDs.
pub(crate) struct LedFilters {
    filters: Option<Vec<CvFilter>>,
}

impl LedFilters {
    /// One filter per LED (`leds`) for `filter`.
    pub fn new(filter: &TrackFilter, leds: usize) -> Self {
        Self {
            filters: match filter {
                TrackFilter::ConstantVelocity(o) => Some(vec![CvFilter::new(*o); leds]),
                _ => None,
            },
        }
    }

    /// Whether the rows carry velocities.
    pub fn active(&self) -> bool {
        self.filters.is_some()
    }

    /// Filters a window's fixes (at `t0`) in place.
    pub fn apply(&mut self, t0: f64, fixes: &mut [LedFix]) {
        let Some(filters) = self.filters.as_mut() else {
            return;
        };
        for (filter, fix) in filters.iter_mut().zip(fixes) {
            let step = filter.step(t0, fix.position);
            match (filter.state(), step) {
                (Some(state), _) if step != FilterStep::Lost => {
                    fix.position = Some((state.position(), state.position_covariance()));
                    fix.velocity = Some(state.velocity());
                    if let Some(status) = step.status() {
                        fix.status = status.to_string();
                    }
                }
                _ => {
                    fix.position = None;
                    fix.velocity = None;
                }
            }
        }
    }
}

/// A window's row of one LED (the velocity columns when `velocity`).
pub(crate) fn row_text(t0: f64, fix: &LedFix, velocity: bool) -> String {
    let led = psdcal_io::csv_field(&fix.led);
    let sensors: Vec<String> = fix
        .sensors
        .iter()
        .map(|s| psdcal_io::csv_field(s))
        .collect();
    let sensors = sensors.join(";");
    let snr = fix.snr_db.map_or(String::new(), num);
    let mut row = match &fix.position {
        Some((p, c)) => format!(
            "{},{led},{sensors},{},{},{},{},{snr},{}",
            num(t0),
            num(p.x),
            num(p.y),
            num(p.z),
            covariance_fields(c).join(","),
            fix.status
        ),
        None => format!("{},{led},{sensors},,,,,,,,,,,{snr},{}", num(t0), fix.status),
    };
    if velocity {
        match &fix.velocity {
            Some(v) => row += &format!(",{},{},{}", num(v.x), num(v.y), num(v.z)),
            None => row += ",,,",
        }
    }
    row
}

impl TrackRig {
    /// Reads rig.json and its calibrations (within `limits`).
    pub fn load(path: &Path, limits: psdcal_io::ReadLimits) -> Result<Self> {
        let mut warnings = Vec::new();
        let (_, rig) = load_rig(path, limits, &mut warnings)?;
        Ok(Self { rig })
    }

    /// The sensors' identifiers in rig.json's order.
    pub fn ids(&self) -> Vec<String> {
        self.rig.sensors().iter().map(|s| s.id.clone()).collect()
    }

    /// The rig.
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    /// One window's answers: a position per LED.
    pub fn fixes(
        &self,
        tones: &Tones,
        estimates: &[std::result::Result<RecordEstimate<4>, SignalError>],
    ) -> Vec<LedFix> {
        let mut fixes = Vec::with_capacity(tones.tones.len());
        for (k, tone) in tones.tones.iter().enumerate() {
            let mut rays = Vec::new();
            let mut ids = Vec::new();
            let mut snr = f64::INFINITY;
            let mut status = "too_few_sensors".to_string();
            let mut per_sensor = Vec::with_capacity(estimates.len());
            for (s, estimate) in estimates.iter().enumerate() {
                let est = match estimate {
                    Ok(est) => est,
                    Err(e) => {
                        per_sensor.push((None, e.status().to_string()));
                        continue;
                    }
                };
                let t = &est.tones[k];
                let sensor_snr = Some(t.min_snr_db()).filter(|v| v.is_finite());
                if t.dark {
                    per_sensor.push((sensor_snr, "dark".to_string()));
                    continue;
                }
                let sensor = &self.rig.sensors()[s];
                let amps = Amplitudes::from(t.amplitudes);
                let Ok((_, j)) = impact_point_amplitude_jacobian(&sensor.sensor.geometry, &amps)
                else {
                    per_sensor.push((sensor_snr, "no_impact_point".to_string()));
                    continue;
                };
                let mut trace = 0.0;
                for r in 0..2 {
                    for c in 0..4 {
                        trace += (j[(r, c)] * t.amplitude_std[c]).powi(2);
                    }
                }
                let options = LocateOptions {
                    point_sigma_mm: (trace / 2.0).sqrt(),
                    ..LocateOptions::default()
                };
                match sensor.sensor.aoa(&Measurement::Amplitudes(amps), &options) {
                    Ok(answer) => {
                        rays.push(WorldRay {
                            sensor: sensor.id.clone(),
                            world_from_sensor: sensor.world_from_sensor,
                            ray_ab: answer.aoa.ray_ab,
                            covariance_ab: answer.ray_covariance(),
                        });
                        ids.push(sensor.id.clone());
                        snr = snr.min(t.min_snr_db());
                        per_sensor.push((sensor_snr, "ok".to_string()));
                    }
                    Err(e) => {
                        status = e.status().to_string();
                        per_sensor.push((sensor_snr, status.clone()));
                    }
                }
            }
            let mut fix = LedFix {
                led: tone.led.clone(),
                sensors: ids,
                position: None,
                velocity: None,
                snr_db: Some(snr).filter(|v| v.is_finite()),
                status: String::new(),
                per_sensor,
            };
            if rays.len() >= 2 {
                match triangulate(&rays, &LocateOptions::default()) {
                    Ok(t) => {
                        fix.position = Some((t.position, t.covariance));
                        fix.status = status_of(&t.cautions).to_string();
                    }
                    Err(e) => fix.status = e.status().to_string(),
                }
            } else {
                fix.status = match estimates.iter().find_map(|e| e.as_ref().err()) {
                    Some(e) if rays.is_empty() => e.status().to_string(),
                    _ if rays.is_empty()
                        && estimates
                            .iter()
                            .all(|e| e.as_ref().is_ok_and(|e| e.tones[k].dark)) =>
                    {
                        "dark".to_string()
                    }
                    _ => status.clone(),
                };
            }
            fixes.push(fix);
        }
        fixes
    }
}
