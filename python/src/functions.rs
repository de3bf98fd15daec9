//! `psdcal.calibrate`, `psdcal.simulate` and `psdcal.demodulate`: Python
//! arguments → the facade's requests (option values parsed by the facade's
//! own parsers) → results as `Calibration`, dicts and numpy arrays.

use numpy::ndarray::{Array1, Array2};
use numpy::IntoPyArray;
use psdcal::arrays::{data_set, PointsInput};
use psdcal::option_text::{parse_images, parse_lens, parse_snr, parse_template_kind};
use psdcal::parse_record_cycles;
use pyo3::exceptions::PyUserWarning;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::calibration::Calibration;
use crate::input::{number, option_text, path, path_or_table};
use crate::{error, input_error};

/// Issues `message` as a Python `UserWarning` (what the command line
/// prints as `warning: …`).
fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let category = py.get_type::<PyUserWarning>();
    let text = std::ffi::CString::new(message.replace('\0', " "))
        .map_err(|e| input_error(e.to_string()))?;
    PyErr::warn(py, &category, &text, 1)
}

/// The `(name, values)` pairs of the keyword options.
fn option_pairs(
    fit: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<(String, Vec<String>)>> {
    let mut pairs = Vec::new();
    if let Some(fit) = fit {
        pairs.push(("fit".to_string(), vec![option_text(fit)?]));
    }
    if let Some(options) = options {
        for (key, value) in options.iter() {
            let name: String = key.extract()?;
            if value.is_none() {
                continue;
            }
            let values = if name == "set" {
                if let Ok(d) = value.cast::<PyDict>() {
                    let mut v = Vec::new();
                    for (k, x) in d.iter() {
                        v.push(format!("{}={}", option_text(&k)?, option_text(&x)?));
                    }
                    v
                } else if value.is_instance_of::<pyo3::types::PyString>() {
                    vec![value.extract::<String>()?]
                } else if let Ok(items) = value.extract::<Vec<String>>() {
                    items
                } else {
                    vec![option_text(&value)?]
                }
            } else {
                vec![option_text(&value)?]
            };
            pairs.push((name, values));
        }
    }
    Ok(pairs)
}

/// Calibrates a sensor from images of an LED template, as `psdcal
/// calibrate` does, and returns the `Calibration`.
///
/// `template` and exactly one of `observations` (impact points) and
/// `signals` (electrode amplitudes) are each a path to the CSV file or an
/// array (see `help(psdcal)`). The options are the command line's, as
/// keywords with the same values: `fit="f,cx,cy,k1,k2"` (or a list; add
/// `gains` with signals), `focal_guess=8.0`, `cost="template"|"image"`,
/// `noise="uniform"|"channel-snr"|"channel-floor"`,
/// `preliminary="auto"|"straightness"|"homography"|"off"`, `normalize=True`,
/// `robust="huber:2.5"`, `uncertainty="linear"|"bootstrap:N[:SEED]"`,
/// `psd_map=PATH`, `set={"l1": -1.3e-3}` (or `["l1=-1.3e-3"]`), `gains=PATH`
/// (gains.json, with signals), `lx=9.0`, `ly=9.0` (active area, mm),
/// `strict=False`. Data dropped and the fit's diagnostics are issued as
/// `UserWarning`s; every failure raises `PsdcalError`.
#[pyfunction]
#[pyo3(signature = (template, observations=None, signals=None, fit=None, **options))]
pub fn calibrate(
    py: Python<'_>,
    template: &Bound<'_, PyAny>,
    observations: Option<&Bound<'_, PyAny>>,
    signals: Option<&Bound<'_, PyAny>>,
    fit: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Calibration> {
    let settings = psdcal::calibrate_settings(&option_pairs(fit, options)?)
        .map_err(|m| error(&psdcal::Error::Options(m)))?;
    let template = path_or_table(template, "template")?;
    let points = match (observations, signals) {
        (Some(o), None) => path_or_table(o, "observations").map(|g| (g, false))?,
        (None, Some(s)) => path_or_table(s, "signals").map(|g| (g, true))?,
        _ => {
            return Err(input_error(
                "calibrate: give exactly one of observations= (impact points) and signals= \
                 (electrode amplitudes)",
            ))
        }
    };
    let (calibrated, warnings) = py
        .detach(|| {
            let input = if points.1 {
                PointsInput::Signals(points.0.input())
            } else {
                PointsInput::Observations(points.0.input())
            };
            let set = data_set(
                &template.input(),
                &input,
                settings.gains.as_ref(),
                &settings.load,
            )?;
            let mut warnings: Vec<String> = set.warnings().iter().map(|w| w.to_string()).collect();
            let mut calibrated = psdcal::calibrate(&set, &settings.options)?;
            calibrated.set_command("psdcal.calibrate (Python)");
            warnings.extend(calibrated.report.warnings.iter().map(|w| w.to_string()));
            warnings.extend(
                calibrated
                    .report
                    .diagnostics
                    .iter()
                    .map(|d| d.message.clone()),
            );
            Ok::<_, psdcal::Error>((calibrated, warnings))
        })
        .map_err(|e| error(&e))?;
    for w in &warnings {
        warn(py, w)?;
    }
    Calibration::of_record(calibrated.record)
}

/// Parses an option's text with `parser`, naming the option in the error.
fn parsed<T>(
    name: &str,
    value: &Bound<'_, PyAny>,
    parser: impl Fn(&str) -> Result<T, String>,
) -> PyResult<T> {
    parser(&option_text(value)?)
        .map_err(|m| error(&psdcal::Error::Options(format!("option {name}: {m}"))))
}

/// A `(rows, K)` array.
fn rows<'py, const K: usize>(py: Python<'py>, rows: Vec<[f64; K]>) -> PyResult<Bound<'py, PyAny>> {
    let n = rows.len();
    let flat: Vec<f64> = rows.into_iter().flatten().collect();
    let a = Array2::from_shape_vec((n, K), flat).map_err(|e| input_error(e.to_string()))?;
    Ok(a.into_pyarray(py).into_any())
}

/// An identifier written by the simulator as a number.
fn id_number(id: &str) -> PyResult<f64> {
    id.parse::<f64>()
        .map_err(|_| input_error(format!("simulated identifier '{id}' is not a number")))
}

/// Simulates a calibration data set through the whole signal chain, as
/// `psdcal simulate --lens L --snr S --images N --seed K` does, and returns
/// it in memory as a dict: `template` `(N, 2)` (LEDs 1 … N), `observations`
/// `(M, 4)`, `signals` `(M, 6)` (ready for `psdcal.calibrate`), `truth` (the
/// true parameters by name, gains too), `poses` `(images, 6)` (`rx, ry, rz,
/// tx, ty, tz`, the true sensor_from_template poses) and `description`.
/// `noise=False` simulates without noise (`snr_db` is then ignored).
#[pyfunction]
#[pyo3(
    signature = (lens=None, snr_db=None, images=None, seed=None, imbalance=false, psd_distortion=false, psd_nonlinearity=false, template=None, record_cycles=None, noise=true),
    text_signature = "(lens=2, snr_db=40.0, images=9, seed=1, imbalance=False, psd_distortion=False, psd_nonlinearity=False, template='scatter14', record_cycles=65, noise=True)"
)]
#[allow(clippy::too_many_arguments)]
pub fn simulate<'py>(
    py: Python<'py>,
    lens: Option<&Bound<'py, PyAny>>,
    snr_db: Option<&Bound<'py, PyAny>>,
    images: Option<&Bound<'py, PyAny>>,
    seed: Option<&Bound<'py, PyAny>>,
    imbalance: bool,
    psd_distortion: bool,
    psd_nonlinearity: bool,
    template: Option<&Bound<'py, PyAny>>,
    record_cycles: Option<&Bound<'py, PyAny>>,
    noise: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let request = psdcal::SimulateRequest {
        lens: lens.map_or(Ok(psdcal::Lens::Two), |v| parsed("lens", v, parse_lens))?,
        snr_db: if noise {
            Some(snr_db.map_or(Ok(40.0), |v| parsed("snr_db", v, parse_snr))?)
        } else {
            None
        },
        imbalance,
        psd_distortion,
        psd_nonlinearity,
        images: images.map_or(Ok(9), |v| parsed("images", v, parse_images))?,
        template: template.map_or(Ok(psdcal::TemplateKind::Scatter14), |v| {
            parsed("template", v, parse_template_kind)
        })?,
        record_cycles: record_cycles.map_or(Ok(psdcal::DEFAULT_RECORD_CYCLES), |v| {
            parsed("record_cycles", v, parse_record_cycles)
        })?,
        seed: seed.map_or(Ok(1), crate::input::seed)?,
        out: std::path::PathBuf::new(),
        force: false,
    };
    let data = py
        .detach(|| psdcal::simulate_data(&request))
        .map_err(|e| error(&e))?;
    let d = PyDict::new(py);
    d.set_item("description", &data.description)?;
    d.set_item(
        "template",
        rows(py, data.template.iter().map(|l| [l.x_mm, l.y_mm]).collect())?,
    )?;
    let mut obs = Vec::with_capacity(data.observations.len());
    for o in &data.observations {
        obs.push([id_number(&o.image)?, id_number(&o.led)?, o.x_mm, o.y_mm]);
    }
    d.set_item("observations", rows(py, obs)?)?;
    let mut sig = Vec::with_capacity(data.signals.len());
    for s in &data.signals {
        let a = &s.amplitudes;
        sig.push([
            id_number(&s.image)?,
            id_number(&s.led)?,
            a.vx1,
            a.vx2,
            a.vy1,
            a.vy2,
        ]);
    }
    d.set_item("signals", rows(py, sig)?)?;
    let t = &data.truth;
    let truth = PyDict::new(py);
    let i = &t.intrinsics;
    let k = &t.distortion;
    for (name, value) in [
        ("f", i.f_mm),
        ("cx", i.cx_mm),
        ("cy", i.cy_mm),
        ("skew", i.skew),
        ("k1", k.k1),
        ("k2", k.k2),
        ("k3", k.k3),
        ("p1", k.p1),
        ("p2", k.p2),
        ("l1", k.l1),
        ("l2", k.l2),
        ("g_x2", t.gains.x2),
        ("g_y1", t.gains.y1),
        ("g_y2", t.gains.y2),
    ] {
        truth.set_item(name, value)?;
    }
    d.set_item("truth", truth)?;
    let poses: Vec<[f64; 6]> = t
        .images
        .iter()
        .map(|p| {
            [
                p.rvec[0], p.rvec[1], p.rvec[2], p.t_mm[0], p.t_mm[1], p.t_mm[2],
            ]
        })
        .collect();
    d.set_item("poses", rows(py, poses)?)?;
    Ok(d)
}

/// Demodulates a raw recording (raw.csv or raw.npy; `rate` in Hz, needed by
/// raw.npy) with its schedule (schedule.csv) and, for frequency
/// multiplexing, `tones` (tones.csv), as `psdcal demodulate` does. Returns a
/// dict: `image`, `led` (lists of identifiers), `amplitudes` `(M, 4)`
/// (`vx1, vx2, vy1, vy2`, peak volts) and `snr_db` `(M,)` of the records
/// demodulated, `status` (every (image, LED) → `ok`, `too_short`,
/// `saturated`, `dark` or `tone_collision`), `sample_rate_hz` and
/// `warnings`; also writes signals.csv when `out` is given.
#[pyfunction]
#[pyo3(
    signature = (raw, rate=None, schedule=None, tones=None, frequency=None, full_scale=None, out=None),
    text_signature = "(raw, rate=None, schedule=None, tones=None, frequency=1000.0, full_scale=10.0, out=None)"
)]
#[allow(clippy::too_many_arguments)]
pub fn demodulate<'py>(
    py: Python<'py>,
    raw: &Bound<'py, PyAny>,
    rate: Option<&Bound<'py, PyAny>>,
    schedule: Option<&Bound<'py, PyAny>>,
    tones: Option<&Bound<'py, PyAny>>,
    frequency: Option<&Bound<'py, PyAny>>,
    full_scale: Option<&Bound<'py, PyAny>>,
    out: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let rate = rate.map(|r| number(r, "rate")).transpose()?;
    let frequency = frequency.map_or(Ok(1000.0), |f| number(f, "frequency"))?;
    let full_scale = full_scale.map_or(Ok(10.0), |f| number(f, "full_scale"))?;
    let schedule = match schedule {
        Some(s) => path(s, "schedule")?,
        None => return Err(input_error("demodulate: give schedule= (schedule.csv)")),
    };
    let raw = path(raw, "raw")?;
    let tones = tones.map(|t| path(t, "tones")).transpose()?;
    let (out, _scratch) = match out {
        Some(o) => (path(o, "out")?, None),
        None => {
            let dir = tempfile::tempdir()
                .map_err(|e| input_error(format!("cannot create a temporary folder: {e}")))?;
            (dir.path().join("signals.csv"), Some(dir))
        }
    };
    let request = psdcal::DemodulateRequest {
        raw,
        rate_hz: rate,
        schedule,
        tones,
        frequency_hz: frequency,
        out,
        // A .tdms recording's default channels (docs/formats.md, raw.tdms).
        channels: Vec::new(),
        config: psdcal::DemodConfig {
            full_scale_v: full_scale,
            ..psdcal::DemodConfig::default()
        },
        limits: psdcal::ReadLimits::default(),
    };
    let done = py
        .detach(|| psdcal::demodulate(&request))
        .map_err(|e| error(&e))?;
    for w in &done.warnings {
        warn(py, w)?;
    }
    let ok: Vec<_> = done
        .records
        .iter()
        .filter_map(|r| Some((r, r.amplitudes?, r.snr_db?)))
        .collect();
    let d = PyDict::new(py);
    d.set_item(
        "image",
        PyList::new(py, ok.iter().map(|(r, _, _)| &r.image))?,
    )?;
    d.set_item("led", PyList::new(py, ok.iter().map(|(r, _, _)| &r.led))?)?;
    d.set_item(
        "amplitudes",
        rows(py, ok.iter().map(|(_, a, _)| *a).collect())?,
    )?;
    let snr: Vec<f64> = ok.iter().map(|(_, _, s)| *s).collect();
    d.set_item("snr_db", Array1::from(snr).into_pyarray(py))?;
    let status = PyDict::new(py);
    for r in &done.records {
        status.set_item((&r.image, &r.led), r.status.name())?;
    }
    d.set_item("status", status)?;
    d.set_item("sample_rate_hz", done.sample_rate_hz)?;
    d.set_item("warnings", PyList::new(py, &done.warnings)?)?;
    Ok(d)
}
