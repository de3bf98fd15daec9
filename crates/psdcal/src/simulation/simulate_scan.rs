//! `psdcal simulate-scan`: a simulated lensless raster scan of the bare PSD
//! (docs/model.md §8.3) written as scan.csv with both forms (measured points
//! and electrode amplitudes), so a scan can be rehearsed before stage time
//! is bought, and tests have ground truth.

use std::path::PathBuf;

use psdcal_io::write_scan;
use psdcal_model::PsdGeometry;
use psdcal_sim::{simulate_scan, ScanOptions, ScanSample};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::base::error::Result;

/// What `simulate-scan` is asked to do.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanRequest {
    /// Raster step, mm.
    pub step_mm: f64,
    /// Stage positioning σ per axis, µm.
    pub stage_sigma_um: f64,
    /// Per-channel SNR, dB (no noise when absent).
    pub snr_db: Option<f64>,
    /// Whether the PSD has the simulated non-linearity (else an ideal PSD).
    pub nonlinearity: bool,
    /// The sensor.
    pub geometry: PsdGeometry,
    /// Seed.
    pub seed: u64,
    /// scan.csv.
    pub out: PathBuf,
}

/// A simulated scan.
#[derive(Debug, Clone)]
pub struct SimulatedScan {
    /// Its samples (with the true spots).
    pub samples: Vec<ScanSample>,
    /// One line describing it.
    pub description: String,
}

impl SimulatedScan {
    /// The summary of the scan written to `out`.
    pub fn summary(&self, out: &std::path::Path) -> crate::base::summary::Summary {
        let json =
            serde_json::json!({"out": out.display().to_string(), "points": self.samples.len()});
        let text = format!(
            "{}\nwrote {} ({} points)",
            self.description,
            out.display(),
            self.samples.len()
        );
        crate::base::summary::Summary::new(text, json)
    }
}

/// Simulates the scan (without writing it).
pub fn scan_samples(request: &ScanRequest) -> Result<SimulatedScan> {
    let options = ScanOptions {
        step_mm: request.step_mm,
        stage_sigma_mm: request.stage_sigma_um * 1e-3,
        snr_db: request.snr_db,
        nonlinearity: request.nonlinearity,
        geometry: request.geometry,
        ..ScanOptions::default()
    };
    let samples = simulate_scan(&options, &mut ChaCha8Rng::seed_from_u64(request.seed))?;
    let side = |l: f64| ((l / request.step_mm) * (1.0 + 1e-12)).floor() as usize + 1;
    let description = format!(
        "Simulated lensless scan: {} × {} positions {} mm apart, stage σ {} µm, {}, {}, seed {}.",
        side(request.geometry.lx),
        side(request.geometry.ly),
        request.step_mm,
        request.stage_sigma_um,
        request
            .snr_db
            .map_or("no noise".to_string(), |s| format!("{s} dB SNR")),
        if request.nonlinearity {
            "PSD non-linearity"
        } else {
            "ideal PSD"
        },
        request.seed
    );
    Ok(SimulatedScan {
        samples,
        description,
    })
}

/// Simulates the scan and writes scan.csv.
pub fn simulate_scan_file(request: &ScanRequest) -> Result<SimulatedScan> {
    let scan = scan_samples(request)?;
    let stage: Vec<_> = scan.samples.iter().map(|s| s.stage).collect();
    let measured: Vec<_> = scan.samples.iter().map(|s| s.measured).collect();
    let amplitudes: Vec<_> = scan.samples.iter().map(|s| s.amplitudes).collect();
    write_scan(&request.out, &stage, Some(&measured), Some(&amplitudes))?;
    Ok(scan)
}
