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

use std::path::Path;

use psdcal_io::Tones;
use psdcal_locate::{status_of, triangulate, LocateOptions, Measurement, Rig, WorldRay};
use psdcal_model::psd::impact_point_amplitude_jacobian;
use psdcal_model::Amplitudes;
use psdcal_signal::{RecordEstimate, SignalError};

use crate::answer::locate::load_rig;
use crate::base::error::Result;
use crate::base::table::num;

/// The rig's header.
pub(crate) const HEADER: &str = "t_s,led,sensors,x_world_mm,y_world_mm,z_world_mm,\
sigma_x_world_mm,sigma_y_world_mm,sigma_z_world_mm,cov_xy_world_mm2,cov_xz_world_mm2,\
cov_yz_world_mm2,sigma_position_mm,snr_db,status";

/// A rig ready to track.
pub(crate) struct TrackRig {
    rig: Rig,
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

    /// One window's rows: a position per LED.
    pub fn rows(
        &self,
        tones: &Tones,
        estimates: &[std::result::Result<RecordEstimate<4>, SignalError>],
        t0: f64,
    ) -> Vec<String> {
        let mut rows = Vec::with_capacity(tones.tones.len());
        for (k, tone) in tones.tones.iter().enumerate() {
            let led = psdcal_io::csv_field(&tone.led);
            let mut rays = Vec::new();
            let mut ids = Vec::new();
            let mut snr = f64::INFINITY;
            let mut status = "too_few_sensors".to_string();
            for (s, estimate) in estimates.iter().enumerate() {
                let Ok(est) = estimate else { continue };
                let t = &est.tones[k];
                if t.dark {
                    continue;
                }
                let sensor = &self.rig.sensors()[s];
                let amps = Amplitudes::from(t.amplitudes);
                let Ok((_, j)) = impact_point_amplitude_jacobian(&sensor.sensor.geometry, &amps)
                else {
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
                        ids.push(psdcal_io::csv_field(&sensor.id));
                        snr = snr.min(t.min_snr_db());
                    }
                    Err(e) => status = e.status().to_string(),
                }
            }
            let sensors = ids.join(";");
            let snr_text = if snr.is_finite() {
                num(snr)
            } else {
                String::new()
            };
            let row = if rays.len() >= 2 {
                match triangulate(&rays, &LocateOptions::default()) {
                    Ok(t) => {
                        let p = t.position;
                        let c = t.covariance;
                        let sd = |v: f64| num(v.max(0.0).sqrt());
                        format!(
                            "{},{led},{sensors},{},{},{},{},{},{},{},{},{},{},{snr_text},{}",
                            num(t0),
                            num(p.x),
                            num(p.y),
                            num(p.z),
                            sd(c[(0, 0)]),
                            sd(c[(1, 1)]),
                            sd(c[(2, 2)]),
                            num(c[(0, 1)]),
                            num(c[(0, 2)]),
                            num(c[(1, 2)]),
                            sd(c.trace()),
                            status_of(&t.cautions)
                        )
                    }
                    Err(e) => empty_row(t0, &led, &sensors, &snr_text, e.status()),
                }
            } else {
                let why = match estimates.iter().find_map(|e| e.as_ref().err()) {
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
                empty_row(t0, &led, &sensors, &snr_text, &why)
            };
            rows.push(row);
        }
        rows
    }
}

/// A row without a position.
fn empty_row(t0: f64, led: &str, sensors: &str, snr: &str, status: &str) -> String {
    format!("{},{led},{sensors},,,,,,,,,,,{snr},{status}", num(t0))
}
