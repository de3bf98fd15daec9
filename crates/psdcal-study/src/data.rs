//! A simulated data set as the calibration's input (psdcal-sim knows
//! nothing of psdcal-calib; this crate joins them).

use psdcal_calib::{CalibrationData, ImageObservations, Observation};
use psdcal_sim::Simulation;

/// The calibration's input of a simulated data set.
pub trait SimulationData {
    /// The measured points of every image, with the demodulated amplitudes
    /// behind them (for estimating the gains).
    fn calibration_data(&self) -> CalibrationData;
}

impl SimulationData for Simulation {
    fn calibration_data(&self) -> CalibrationData {
        CalibrationData {
            noise_scale: None,
            amplitudes: Some(
                self.images
                    .iter()
                    .map(|im| im.points.iter().map(|p| p.amplitudes).collect())
                    .collect(),
            ),
            template: self.template.leds.clone(),
            lines: self.template.lines.clone(),
            images: self
                .images
                .iter()
                .map(|im| ImageObservations {
                    id: im.id.clone(),
                    points: im
                        .points
                        .iter()
                        .map(|p| Observation {
                            led: p.led,
                            measured: p.measured,
                        })
                        .collect(),
                })
                .collect(),
            geometry: self.options.geometry,
        }
    }
}
