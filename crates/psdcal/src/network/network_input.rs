//! The files of a network calibration (docs/formats.md, "Network
//! calibration") read into [`NetworkData`]: each sensor's lab
//! calibration.json becomes its model and prior (the lab-estimated lens
//! parameters with their covariance; gains rows left out: the sightings
//! are impact points), the wand and the static frame their LEDs, and every
//! row of network_points.csv one observation (amplitudes converted with the
//! sensor's size and lab gains). Frames are numbered in order of first
//! appearance; static-frame LEDs may carry any frame.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use nalgebra::DMatrix;
use psdcal_io::{
    read_calibration_with, Calibration, InputFile, LedPositions, NetworkPoints, NetworkSensors,
    PointInput, ReadLimits,
};
use psdcal_model::Model;
use psdcal_network::{Led, NetworkData, NetworkObservation, NetworkSensor};

use crate::base::error::{Error, Result};
use crate::base::provenance::sha256_hex;

/// The input files.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct NetworkFiles {
    /// sensors.csv: `sensor`, `calibration` (each sensor's lab calibration.json)
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE"))]
    pub sensors: PathBuf,
    /// wand.csv: `led`, `X_mm`, `Y_mm`, `Z_mm` in the wand's frame
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE"))]
    pub wand: PathBuf,
    /// network_points.csv: `frame`, `sensor`, `led`, `x_mm`, `y_mm` (or vx1, vx2, vy1, vy2)
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE"))]
    pub observations: PathBuf,
    /// frame.csv (optional): the static frame's LEDs at known world positions
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE"))]
    pub frame: Option<PathBuf>,
}

/// Everything read.
#[derive(Debug, Clone)]
pub struct NetworkInput {
    /// The data for the calibration.
    pub data: NetworkData,
    /// Each sensor's lab record and its path.
    pub labs: Vec<(Calibration, PathBuf)>,
    /// Every file read with its hash.
    pub inputs: Vec<InputFile>,
}

fn hashed(path: &Path) -> Result<InputFile> {
    let bytes = std::fs::read(path).map_err(|e| psdcal_io::IoError::Read {
        file: path.display().to_string(),
        source: e,
    })?;
    Ok(InputFile {
        path: path.display().to_string(),
        sha256: sha256_hex(&bytes),
    })
}

/// One sensor from its lab record.
fn sensor_of(id: &str, lab: &Calibration, path: &Path) -> Result<NetworkSensor> {
    if lab.psd_map.is_some() {
        return Err(Error::Input(format!(
            "sensor '{id}': {} holds a PSD map; a network calibration refines the standard lens \
             model only: give a lab calibration without --psd-map",
            path.display()
        )));
    }
    let names: Vec<String> = lab.estimated.iter().map(|p| p.name().to_string()).collect();
    let cov = &lab.covariance;
    let index = |n: &str| cov.parameters.iter().position(|p| p == n);
    let rows: Vec<usize> = names.iter().filter_map(|n| index(n)).collect();
    if rows.len() != names.len() {
        return Err(Error::Input(format!(
            "sensor '{id}': {} has no covariance for its estimated parameters ({}); a network \
             calibration uses the lab covariance as the prior: recalibrate with psdcal calibrate",
            path.display(),
            names.join(", ")
        )));
    }
    let prior_covariance =
        DMatrix::from_fn(rows.len(), rows.len(), |i, j| cov.matrix[rows[i]][rows[j]]);
    Ok(NetworkSensor {
        id: id.to_string(),
        model: Model::standard(&lab.to_model()),
        prior_names: names,
        prior_covariance,
        geometry: lab.geometry(),
    })
}

/// Reads the files (module documentation).
pub fn read_network(files: &NetworkFiles, limits: ReadLimits) -> Result<NetworkInput> {
    let sensors_file = NetworkSensors::read_with(&files.sensors, limits)?;
    let wand = LedPositions::read_with(&files.wand, limits)?;
    let frame = files
        .frame
        .as_ref()
        .map(|p| LedPositions::read_with(p, limits))
        .transpose()?;
    let points = NetworkPoints::read_with(&files.observations, limits)?;
    let mut inputs = vec![hashed(&files.sensors)?, hashed(&files.wand)?];
    if let Some(p) = &files.frame {
        inputs.push(hashed(p)?);
    }
    inputs.push(hashed(&files.observations)?);
    let mut labs = Vec::new();
    let mut sensors = Vec::new();
    for row in &sensors_file.rows {
        let lab = read_calibration_with(&row.calibration_path, limits)?;
        inputs.push(hashed(&row.calibration_path)?);
        sensors.push(sensor_of(&row.sensor, &lab, &row.calibration_path)?);
        labs.push((lab, row.calibration_path.clone()));
    }
    let sensor_index: HashMap<&str, usize> = sensors_file
        .rows
        .iter()
        .enumerate()
        .map(|(k, r)| (r.sensor.as_str(), k))
        .collect();
    let mut leds: HashMap<&str, Led> = HashMap::new();
    for (k, n) in wand.names.iter().enumerate() {
        leds.insert(n, Led::Wand(k));
    }
    if let Some(f) = &frame {
        for (k, n) in f.names.iter().enumerate() {
            if leds.insert(n, Led::Frame(k)).is_some() {
                return Err(Error::Input(format!(
                    "LED '{n}' is in both {} and {}: name the wand's and the frame's LEDs apart",
                    wand.source, f.source
                )));
            }
        }
    }
    let mut frame_index: HashMap<&str, usize> = HashMap::new();
    let mut frames = Vec::new();
    let mut observations = Vec::with_capacity(points.rows.len());
    let mut seen: HashMap<(usize, usize, Led), usize> = HashMap::new();
    for row in &points.rows {
        let at = || format!("{}:{}", points.source, row.line_no);
        let &sensor = sensor_index.get(row.sensor.as_str()).ok_or_else(|| {
            Error::Input(format!(
                "{}: sensor '{}' is not in {}",
                at(),
                row.sensor,
                sensors_file.source
            ))
        })?;
        let &led = leds.get(row.led.as_str()).ok_or_else(|| {
            Error::Input(format!(
                "{}: LED '{}' is neither a wand LED ({}) nor a frame LED{}",
                at(),
                row.led,
                wand.source,
                frame
                    .as_ref()
                    .map_or(" (no --frame given)".to_string(), |f| format!(
                        " ({})",
                        f.source
                    ))
            ))
        })?;
        let f = *frame_index.entry(row.frame.as_str()).or_insert_with(|| {
            frames.push(row.frame.clone());
            frames.len() - 1
        });
        let measured = match &row.input {
            PointInput::Position(p) => *p,
            PointInput::Amplitudes(a) => {
                let lab = &labs[sensor].0;
                let gains = lab.gains().unwrap_or(psdcal_model::ChannelGains::UNIT);
                psdcal_model::psd::impact_point_with_gains(&lab.geometry(), a, &gains)
                    .map_err(|e| Error::Input(format!("{}: {e}", at())))?
            }
            _ => {
                return Err(Error::Input(format!(
                    "{}: a value is not a finite number",
                    at()
                )))
            }
        };
        if matches!(led, Led::Wand(_)) {
            if let Some(first) = seen.insert((f, sensor, led), row.line_no) {
                return Err(Error::Input(format!(
                    "{}: sensor '{}' saw LED '{}' twice in frame '{}' (first on line {first})",
                    at(),
                    row.sensor,
                    row.led,
                    row.frame
                )));
            }
        }
        observations.push(NetworkObservation {
            frame: f,
            sensor,
            led,
            measured,
        });
    }
    let data = NetworkData {
        sensors,
        wand: wand.positions,
        wand_names: wand.names,
        frame_leds: frame
            .as_ref()
            .map(|f| f.positions.clone())
            .unwrap_or_default(),
        frame_names: frame.map(|f| f.names).unwrap_or_default(),
        frames,
        observations,
    };
    Ok(NetworkInput { data, labs, inputs })
}
