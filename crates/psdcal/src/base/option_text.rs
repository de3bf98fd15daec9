//! The text forms of options (`--fit f,cx,cy,k1,k2`, `--robust huber:2.5`,
//! `--uncertainty bootstrap:200:7`, `--set l1=-1.3e-3`, lengths in mm): one
//! parser each, shared by every front end (the command line, the Python
//! package), so that the same text means the same everywhere and is refused
//! with the same message.

use nalgebra::Vector3;
use psdcal_locate::{Plane, MAX_GRID};
use psdcal_model::{Param, UnknownParam};

use psdcal_calib::{BootstrapOptions, RobustLoss, Uncertainty};

/// What `--fit` frees: standard parameters, the amplifier gains, the
/// aspect stage's `a` (docs/model.md §3.3).
#[derive(Debug, Clone, PartialEq)]
pub struct FitList {
    /// The standard parameters.
    pub params: Vec<Param>,
    /// The amplifier gains (`gains`).
    pub gains: bool,
    /// The y axis's own scale (`a`, `fy = f (1 + a)`).
    pub aspect: bool,
}

impl FitList {
    /// `params` alone.
    pub fn of(params: Vec<Param>) -> Self {
        Self {
            params,
            gains: false,
            aspect: false,
        }
    }
}

/// `--fit LIST`: parameter names separated by commas, `gains` for the
/// amplifier gains, `a` for the aspect; each at most once, at least one
/// standard parameter.
pub fn parse_fit(text: &str) -> Result<FitList, String> {
    let mut out = FitList::of(Vec::new());
    for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let flag = if name.eq_ignore_ascii_case("gains") {
            Some(&mut out.gains)
        } else if name == psdcal_model::stages::Aspect::NAME {
            Some(&mut out.aspect)
        } else {
            None
        };
        if let Some(flag) = flag {
            if *flag {
                return Err(format!("'{name}' is listed twice"));
            }
            *flag = true;
            continue;
        }
        let p: Param = name.parse().map_err(|e: UnknownParam| {
            format!("{e} (or gains, or a for the y axis's own scale)")
        })?;
        if out.params.contains(&p) {
            return Err(format!("'{p}' is listed twice"));
        }
        out.params.push(p);
    }
    if out.params.is_empty() {
        return Err("expected at least one parameter, e.g. f,cx,cy,k1,k2".into());
    }
    Ok(out)
}

/// `--robust LOSS:SCALE`: `huber:SCALE` or `cauchy:SCALE`, SCALE in units of
/// the residuals' noise σ (estimated from the data; at least 1).
pub fn parse_robust(text: &str) -> Result<RobustLoss, String> {
    let (kind, scale) = text
        .split_once(':')
        .ok_or_else(|| format!("expected LOSS:SCALE such as huber:2.5, found '{text}'"))?;
    let scale: f64 = scale
        .trim()
        .parse()
        .map_err(|_| format!("expected a number for the scale, found '{scale}'"))?;
    if !(scale.is_finite() && scale >= 1.0) {
        return Err(format!(
            "the scale {scale} is in units of the residuals' noise σ (estimated from the data): \
             give 1 or more (2–3 is typical); under 1 most good points would count as outliers"
        ));
    }
    match kind.trim().to_ascii_lowercase().as_str() {
        "huber" => Ok(RobustLoss::Huber { scale }),
        "cauchy" => Ok(RobustLoss::Cauchy { scale }),
        other => Err(format!("unknown loss '{other}' (expected huber or cauchy)")),
    }
}

/// `--uncertainty linear`, `bootstrap:N` or `bootstrap:N:SEED`.
/// `--uncertainty jackknife|linear|bootstrap:N[:SEED]` (N ≥ 10, seed 1 by
/// default).
pub fn parse_uncertainty(text: &str) -> Result<Uncertainty, String> {
    let mut parts = text.split(':');
    match parts
        .next()
        .map(|p| p.trim().to_ascii_lowercase())
        .as_deref()
    {
        Some("linear") if parts.next().is_none() => Ok(Uncertainty::Linear),
        Some("jackknife") if parts.next().is_none() => Ok(Uncertainty::Jackknife),
        Some("bootstrap") => {
            let number = |part: Option<&str>, what: &str| -> Result<Option<u64>, String> {
                part.map(|p| {
                    p.trim()
                        .parse::<u64>()
                        .map_err(|_| format!("expected a whole number for the {what}, found '{p}'"))
                })
                .transpose()
            };
            let resamples = number(parts.next(), "resamples")?
                .ok_or("expected bootstrap:N, e.g. bootstrap:200")?;
            if resamples < 10 {
                return Err(format!(
                    "the bootstrap needs at least 10 resamples, not {resamples}"
                ));
            }
            let seed = number(parts.next(), "seed")?.unwrap_or(1);
            if parts.next().is_some() {
                return Err(format!("expected bootstrap:N[:SEED], found '{text}'"));
            }
            Ok(Uncertainty::Bootstrap(BootstrapOptions {
                resamples: resamples as usize,
                seed,
            }))
        }
        _ => Err(format!(
            "expected jackknife, linear or bootstrap:N[:SEED], found '{text}'"
        )),
    }
}

/// `--set NAME=VALUE`: a parameter and a finite value.
pub fn parse_assignment(text: &str) -> Result<(Param, f64), String> {
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE such as l1=-1.3e-3, found '{text}'"))?;
    let p: Param = name.parse().map_err(|e: UnknownParam| e.to_string())?;
    match value.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok((p, v)),
        _ => Err(format!("expected a finite number for {p}, found '{value}'")),
    }
}

/// The longest length an option accepts, mm (1 000 km): beyond it results
/// overflow or mean a unit error.
pub const MAX_LENGTH_MM: f64 = 1e9;
/// The largest active-area side, mm.
pub const MAX_SIDE_MM: f64 = 1000.0;

/// A positive, finite length in mm, at most [`MAX_LENGTH_MM`].
pub fn positive_mm(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= MAX_LENGTH_MM => Ok(v),
        _ => Err(format!(
            "expected a positive length in mm up to 1e9, found '{text}'"
        )),
    }
}

/// An active-area side: a positive length in mm, at most [`MAX_SIDE_MM`].
pub fn side_mm(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= MAX_SIDE_MM => Ok(v),
        _ => Err(format!(
            "expected the side of the active area, a positive length in mm up to 1000, found \
             '{text}'"
        )),
    }
}

/// A finite number, or `None`.
fn number(text: &str) -> Option<f64> {
    text.trim().parse::<f64>().ok().filter(|v| v.is_finite())
}

/// A non-negative, finite length in mm, at most [`MAX_LENGTH_MM`].
pub fn non_negative_mm(text: &str) -> Result<f64, String> {
    match number(text) {
        Some(v) if (0.0..=MAX_LENGTH_MM).contains(&v) => Ok(v),
        _ => Err(format!(
            "expected a length from 0 to 1e9 mm, found '{text}'"
        )),
    }
}

/// The largest `--k-sigma`.
pub const MAX_K_SIGMA: f64 = 1000.0;

/// `--k-sigma K`: a positive, finite number, at most [`MAX_K_SIGMA`].
pub fn within_k_sigma(text: &str) -> Result<f64, String> {
    match number(text) {
        Some(v) if v > 0.0 && v <= MAX_K_SIGMA => Ok(v),
        _ => Err(format!(
            "expected a positive number up to {MAX_K_SIGMA}, found '{text}'"
        )),
    }
}

/// An angle in degrees, 0 to 90.
pub fn angle_deg(text: &str) -> Result<f64, String> {
    match number(text) {
        Some(v) if (0.0..=90.0).contains(&v) => Ok(v),
        _ => Err(format!(
            "expected an angle from 0 to 90 degrees, found '{text}'"
        )),
    }
}

/// A grid size, 2 to [`MAX_GRID`] points per side.
pub fn grid_size(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if (2..=MAX_GRID).contains(&n) => Ok(n),
        _ => Err(format!(
            "expected 2 to {MAX_GRID} points per side, found '{text}'"
        )),
    }
}

/// `--plane NX,NY,NZ,D`: the plane `n·P = d` in the sensor frame, d in mm.
pub fn parse_plane(text: &str) -> Result<Plane, String> {
    let values: Vec<Option<f64>> = text.split(',').map(number).collect();
    let [Some(nx), Some(ny), Some(nz), Some(d)] = values[..] else {
        return Err(format!(
            "expected four numbers NX,NY,NZ,D (the plane n.P = d, sensor frame, d in mm), found \
             '{text}'"
        ));
    };
    if d.abs() > MAX_LENGTH_MM {
        return Err(format!(
            "expected the plane's D within ±1e9 mm, found '{text}'"
        ));
    }
    Plane::new(Vector3::new(nx, ny, nz), d).map_err(|e| e.to_string())
}

/// `--error f=0.05,cx=0.02`: parameter errors (at least one).
pub fn parse_error_list(text: &str) -> Result<Vec<(Param, f64)>, String> {
    let mut out = Vec::new();
    for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (name, value) = item
            .split_once('=')
            .ok_or_else(|| format!("expected NAME=VALUE such as f=0.05, found '{item}'"))?;
        let p: Param = name.parse().map_err(|e: UnknownParam| e.to_string())?;
        let v = number(value)
            .ok_or_else(|| format!("expected a finite number for {p}, found '{value}'"))?;
        out.push((p, v));
    }
    if out.is_empty() {
        return Err("expected NAME=VALUE such as f=0.05".into());
    }
    Ok(out)
}

/// `--snr DB`: an SNR in dB, −20 to 200.
pub fn parse_snr(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && (-20.0..=200.0).contains(&v) => Ok(v),
        _ => Err(format!(
            "expected an SNR in dB between -20 and 200, found '{text}'"
        )),
    }
}

/// `--images N`: 3 to 100 000 images.
pub fn parse_images(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if (3..=100_000).contains(&n) => Ok(n),
        _ => Err(format!("expected a number of images from 3 to 100000 (a calibration needs at least 3), found '{text}'")),
    }
}

/// `--trials N`: 1 to 1 000 000 Monte Carlo trials.
pub fn parse_trials(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if (1..=1_000_000).contains(&n) => Ok(n),
        _ => Err(format!(
            "expected a number of trials from 1 to 1000000, found '{text}'"
        )),
    }
}

/// `--threads N`: 1 to 1 024 threads.
pub fn parse_threads(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if (1..=1024).contains(&n) => Ok(n),
        _ => Err(format!(
            "expected a number of threads from 1 to 1024, found '{text}'"
        )),
    }
}

/// A switch: `true` or `false` (any case).
pub fn parse_switch(text: &str) -> Result<bool, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "true" => Ok(true),
        "false" => Ok(false),
        _ => Err(format!("expected true or false, found '{text}'")),
    }
}

/// `--distance S`: the plane `z = S` parallel to the sensor, S a positive
/// length in mm.
pub fn plane_at_distance(text: &str) -> Result<Plane, String> {
    Plane::parallel(positive_mm(text)?).map_err(|e| e.to_string())
}

/// `--lens 1|2`: the paper's lens.
pub fn parse_lens(text: &str) -> Result<psdcal_sim::Lens, String> {
    match text.trim() {
        "1" => Ok(psdcal_sim::Lens::One),
        "2" => Ok(psdcal_sim::Lens::Two),
        _ => Err(format!("expected the paper's lens 1 or 2, found '{text}'")),
    }
}

/// `--template scatter14|grid`.
pub fn parse_template_kind(text: &str) -> Result<psdcal_sim::TemplateKind, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "scatter14" => Ok(psdcal_sim::TemplateKind::Scatter14),
        "grid" => Ok(psdcal_sim::TemplateKind::Grid),
        _ => Err(format!("expected scatter14 or grid, found '{text}'")),
    }
}

/// `--sensor LXxLY` (also `--size WxH`): two positive lengths in mm joined
/// by `x`, or one for a square.
pub fn parse_sides_mm(text: &str) -> Result<(f64, f64), String> {
    let (a, b) = text.split_once(['x', 'X']).unwrap_or((text, text));
    let side = |t: &str| {
        positive_mm(t).map_err(|_| {
            format!("expected sides in mm such as 9x9 (or one side for a square), found '{text}'")
        })
    };
    Ok((side(a)?, side(b)?))
}

/// `--distance MIN:MAX`: a range of positive distances in mm.
pub fn parse_range_mm(text: &str) -> Result<(f64, f64), String> {
    let bad = || format!("expected MIN:MAX in mm such as 700:1500, found '{text}'");
    let (a, b) = text.split_once(':').ok_or_else(bad)?;
    let (lo, hi) = (
        positive_mm(a).map_err(|_| bad())?,
        positive_mm(b).map_err(|_| bad())?,
    );
    if hi < lo {
        return Err(format!(
            "--distance {text}: the minimum is above the maximum; give MIN:MAX"
        ));
    }
    Ok((lo, hi))
}
