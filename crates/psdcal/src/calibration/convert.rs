//! The one place that knows psdcal-calib's types: a data set → the
//! calibration's input, the options → its options, and its result → the
//! calibration.json record, the printable fit report and the calibrated
//! sensor. When psdcal-calib's result types change, only this module does.

use std::collections::HashMap;
use std::path::Path;

use psdcal_calib::{
    CalibrateOptions, CalibrationData, CalibrationResult, CostKind, ImageObservations, InitOptions,
    InitRoute, NoiseModel, Observation, RefineOptions,
};
use psdcal_io::{
    BootstrapRecord, Calibration, Covariance, FitSummary, GainsRecord, ImageFit, IoError, Location,
    StdDevs,
};
use psdcal_locate::CalibratedSensor;
use psdcal_model::stages::gains::GAIN_NAMES;
use psdcal_model::stages::{with_aspect, Aspect};
use psdcal_model::{Amplitudes, Model, Param, SensorModel};

use crate::base::options::CalibrationOptions;
use crate::calibration::fit_report::{ChoiceRows, FitReport, GlobalSearch, ImageRow, ParameterRow};
use crate::calibration::loaded_checks::check_loaded;
use crate::dataset::data_set::DataSet;

/// The calibration's input from a validated data set; with
/// `with_amplitudes`, the amplitudes behind every point (for the gains).
pub fn calibration_data(set: &DataSet, with_amplitudes: bool) -> CalibrationData {
    let template = &set.template;
    let mut data = CalibrationData {
        amplitudes: None,
        noise_scale: None,
        template: template
            .leds
            .iter()
            .map(|l| nalgebra::Vector2::new(l.x_mm, l.y_mm))
            .collect(),
        lines: template
            .line_groups()
            .into_iter()
            .filter(|g| g.leds.len() >= 3)
            .map(|g| g.leds)
            .collect(),
        images: set
            .validated
            .images
            .iter()
            .map(|image| ImageObservations {
                id: image.id.clone(),
                points: image
                    .points
                    .iter()
                    .map(|&(led, measured)| Observation { led, measured })
                    .collect(),
            })
            .collect(),
        geometry: set.options.geometry,
    };
    if let (Some(signals), true) = (&set.signals, with_amplitudes) {
        let by_key: HashMap<(&str, &str), Amplitudes> = signals
            .rows
            .iter()
            .map(|r| ((r.image.as_str(), r.led.as_str()), r.amplitudes()))
            .collect();
        data.amplitudes = set
            .validated
            .images
            .iter()
            .map(|im| {
                im.points
                    .iter()
                    .map(|(led, _)| {
                        by_key
                            .get(&(im.id.as_str(), template.leds[*led].id.as_str()))
                            .copied()
                    })
                    .collect()
            })
            .collect();
    }
    data.noise_scale = record_noise_scale(set);
    data
}

/// Each point's channel-noise variance relative to the others' from its
/// record's SNR (signals.csv's `snr_db`, `10^(−SNR/10)`), when every point
/// has one; what the `channel-snr` weighting scales each point by.
fn record_noise_scale(set: &DataSet) -> Option<Vec<Vec<f64>>> {
    let signals = set.signals.as_ref()?;
    let by_key: HashMap<(&str, &str), f64> = signals
        .rows
        .iter()
        .filter_map(|r| Some(((r.image.as_str(), r.led.as_str()), r.snr_db?)))
        .collect();
    set.validated
        .images
        .iter()
        .map(|im| {
            im.points
                .iter()
                .map(|(led, _)| {
                    let snr_db =
                        by_key.get(&(im.id.as_str(), set.template.leds[*led].id.as_str()))?;
                    Some(10f64.powf(-snr_db / 10.0)).filter(|v| v.is_finite() && *v > 0.0)
                })
                .collect()
        })
        .collect()
}

/// psdcal-calib's options.
pub fn calibrate_options(options: &CalibrationOptions) -> CalibrateOptions {
    let mut base = SensorModel::pinhole(options.focal_guess.unwrap_or(8.0), 0.0, 0.0);
    for &(p, value) in &options.fixed {
        base.set(p, value);
    }
    let mut base: Model = base.into();
    let mut free_stage_parameters = Vec::new();
    if options.fit_aspect {
        // The stage is built from a standard chain: it always takes it.
        base = with_aspect(&base, 0.0).unwrap_or(base);
        free_stage_parameters.push(Aspect::NAME.to_string());
    }
    CalibrateOptions {
        init: InitOptions {
            preliminary: options.preliminary,
            normalize: options.normalize,
            focal_guess: options.focal_guess,
            ..InitOptions::default()
        },
        refine: RefineOptions {
            cost: options.cost,
            noise: options.noise,
            free: options.free.clone(),
            fit_gains: options.fit_gains,
            robust: options.robust,
            free_stage_parameters,
            ..RefineOptions::default()
        },
        base,
        uncertainty: options.uncertainty,
        choice: options.choice,
        ..CalibrateOptions::default()
    }
}

/// The estimated model.
pub fn model(result: &CalibrationResult) -> SensorModel {
    result.sensor_model()
}

/// The calibration.json record of a result (without provenance).
pub fn record(
    result: &CalibrationResult,
    data: &CalibrationData,
    set: &DataSet,
    options: &CalibrationOptions,
) -> Calibration {
    let mut file = Calibration::from_model(&result.sensor_model(), &set.options.geometry);
    let free: Vec<Param> = result.free.iter().filter_map(|n| n.parse().ok()).collect();
    file.aspect = result
        .model
        .get(Aspect::NAME)
        .map(|a| psdcal_io::AspectRecord {
            a,
            estimated: result.free.iter().any(|n| n == Aspect::NAME),
        });
    file.set_estimated(&free);
    if let Some(g) = &result.gains {
        file.gains = Some(GainsRecord::new(g, true));
    } else if let Some(g) = &set.known_gains {
        file.gains = Some(GainsRecord::new(g, false));
    }
    let covariance = &result.covariance.parameters;
    file.std = StdDevs(
        covariance
            .names()
            .iter()
            .map(|name| (name.clone(), covariance.std(name).unwrap_or(0.0)))
            .collect(),
    );
    file.covariance = Covariance::from(covariance);
    let stats = &result.statistics;
    file.fit = FitSummary {
        cost: result.cost_kind,
        noise: options.noise.name().to_string(),
        residual_mm2: stats.residual_mm2,
        rms_template_mm: stats.rms_template_mm,
        rms_image_mm: stats.rms_image_mm,
        iterations: result.refine.iterations,
        points: stats.points,
        images: stats.images,
        termination: format!("{:?}", result.refine.termination),
        uncertainty: result.covariance.method.name().to_string(),
        bootstrap: match (result.covariance.method, &result.bootstrap) {
            (psdcal_calib::CovarianceMethod::Bootstrap { resamples, seed }, Some(report)) => {
                Some(BootstrapRecord {
                    resamples,
                    failed: report.failed,
                    seed,
                })
            }
            _ => None,
        },
        model_choice: result
            .model_choice
            .as_ref()
            .and_then(|c| serde_json::to_value(c).ok()),
    };
    file.images = data
        .images
        .iter()
        .zip(&result.poses)
        .zip(&stats.per_image)
        .map(|((image, pose), s)| {
            ImageFit::new(&image.id, pose, s.rms_template_mm, image.points.len())
        })
        .collect();
    file.diagnostics = result.diagnostics.clone();
    file
}

/// The printable view of a result.
pub fn fit_report(r: &CalibrationResult) -> FitReport {
    let s = &r.statistics;
    let aspect = r.model.get(Aspect::NAME).map(|a| ParameterRow {
        name: Aspect::NAME,
        value: a,
        std: r.covariance.parameters.std(Aspect::NAME),
        unit: "1",
    });
    let parameters = Param::ALL
        .iter()
        .map(|&p| ParameterRow {
            name: p.name(),
            value: r.sensor_model().get(p),
            std: r.covariance.std(p),
            unit: p.unit(),
        })
        .chain(aspect)
        .collect();
    let gains = match (&r.gains, r.covariance.gain_std()) {
        (Some(g), Some(sd)) => GAIN_NAMES
            .iter()
            .zip(g.to_array())
            .zip(sd)
            .map(|((name, value), std)| (name.to_string(), value, std))
            .collect(),
        _ => Vec::new(),
    };
    let corr = r.covariance.correlation();
    FitReport {
        images: s.images,
        points: s.points,
        start: match r.init.route {
            InitRoute::ClosedForm => "closed form",
            InitRoute::FocalSearch => "focal-length search (closed form rejected)",
            InitRoute::FocalGuess => "focal-length search around --focal-guess",
        },
        closed_form_rejection: r.init.closed_form_rejection.clone(),
        parameters,
        gains,
        gain_start: r.gain_start.clone(),
        correlation_names: if r.free.len() > 1 {
            r.covariance.names().to_vec()
        } else {
            Vec::new()
        },
        correlation: (0..corr.nrows())
            .map(|i| (0..corr.ncols()).map(|j| corr[(i, j)]).collect())
            .collect(),
        cost: match r.cost_kind {
            CostKind::Template => "template plane",
            CostKind::Image => "image plane",
        },
        robust: r.robust.is_some(),
        noise: match r.noise {
            NoiseModel::Uniform => None,
            noise => Some(noise.name()),
        },
        residual_mm2: s.residual_mm2,
        rms_template_mm: s.rms_template_mm,
        rms_image_mm: s.rms_image_mm,
        iterations: r.refine.iterations,
        termination: format!("{:?}", r.refine.termination),
        global: r.global.as_ref().map(|g| GlobalSearch {
            minima: g.minima.iter().map(|m| [m.cost, m.l1, m.k1, m.f]).collect(),
            refinements: g.refinements,
        }),
        per_image: s
            .per_image
            .iter()
            .map(|i| ImageRow {
                id: i.id.clone(),
                points: i.points,
                rms_template_mm: i.rms_template_mm,
                rms_image_mm: i.rms_image_mm,
            })
            .collect(),
        warnings: psdcal_calib::warning_texts(&r.warnings),
        diagnostics: r.diagnostics.clone(),
        uncertainty: r.covariance.method.name(),
        model_choice: r.model_choice.as_ref().map(|c| ChoiceRows {
            candidates: c
                .candidates
                .iter()
                .map(|k| {
                    let free = k.free.join(",");
                    let held_out = k.held_out_rms_deg.map(|rms| {
                        let l = k.log_ratio.unwrap_or(0.0);
                        (rms, l, k.log_ratio_se.unwrap_or(0.0))
                    });
                    (free, k.score_statistic, held_out, k.accepted)
                })
                .collect(),
            chosen: c.chosen.join(","),
            skipped: c.skipped.clone(),
        }),
    }
}

/// The calibrated sensor of a calibration record: model, sensor size, gains
/// and covariance; `file` names it in errors.
pub fn sensor(calibration: &Calibration, file: &Path) -> Result<CalibratedSensor, IoError> {
    let covariance = calibration
        .covariance
        .to_parameter_covariance()
        .map_err(|message| IoError::Invalid {
            at: Location::file(&file.display().to_string()),
            message,
        })?;
    let mut sensor = CalibratedSensor::new(calibration.to_model(), calibration.geometry());
    if let Some(aspect) = calibration.aspect {
        sensor = sensor.with_aspect(aspect.a);
    }
    if let Some(map) = &calibration.psd_map {
        let mut sensor = crate::calibration::calibrate_map::sensor_with_map(
            map, sensor, covariance,
        )
        .map_err(|message| IoError::Invalid {
            at: Location::file(&file.display().to_string()),
            message,
        })?;
        sensor.gains = calibration.gains();
        check_loaded(calibration, &sensor, file)?;
        return Ok(sensor);
    }
    // The valid region is the one `CalibratedSensor::new` computed from the
    // parameters: a stored one is never trusted (a hand edit keeps it).
    let mut sensor = sensor.with_covariance(covariance);
    sensor.gains = calibration.gains();
    check_loaded(calibration, &sensor, file)?;
    Ok(sensor)
}
