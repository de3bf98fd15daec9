//! `psdcal export`: a calibration as a camera model for OpenCV, mrcal or
//! ROS (docs/model.md §8.7, docs/formats.md "Exported camera models").
//!
//! OpenCV's rational model is fitted over the calibration's valid region
//! (psdcal-locate's `camera_fit`); with a pixel pitch `p` (µm) the sensor's
//! millimetres become pixels, `u = 1000 (x + Lx/2)/p − 0.5`,
//! `v = 1000 (y + Ly/2)/p − 0.5` (no flip), so `fx_px = 1000 fx/p` and
//! `cx_px = 1000 (cx + Lx/2)/p − 0.5`; the coefficients are unchanged.
//! The image is `1000 Lx/p × 1000 Ly/p` pixels (whole numbers: the pitch
//! must divide the sides).
//!
//! The export is refused when the fitted model's largest angle error
//! exceeds `max_error_deg`, with what in the calibration OpenCV's model
//! cannot follow. ROS gets the 5-coefficient `plumb_bob` model when it is
//! within the threshold, else `rational_polynomial`.

use std::path::PathBuf;

use psdcal_io::{write_camera_model, CameraFormat, CameraModelFile};
use psdcal_locate::{fit_opencv, CameraFit, CameraFitOptions, OpenCvKind, OPENCV8_NAMES};
use serde_json::json;

use crate::answer::loaded_sensor::LoadedSensor;
use crate::base::error::{Error, Result};

/// Where the model goes (the variants' docs are `--to`'s help).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ExportTarget {
    /// OpenCV FileStorage YAML (the rational model)
    #[cfg_attr(feature = "clap", value(name = "opencv"))]
    OpenCv,
    /// mrcal .cameramodel (LENSMODEL_OPENCV8)
    Mrcal,
    /// ROS camera_info YAML (plumb_bob or rational_polynomial)
    Ros,
}

impl ExportTarget {
    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ExportTarget::OpenCv => "opencv",
            ExportTarget::Mrcal => "mrcal",
            ExportTarget::Ros => "ros",
        }
    }
}

/// Default pixel pitch, µm.
pub const DEFAULT_PIXEL_UM: f64 = 1.0;
/// Default largest angle error accepted, degrees.
pub const DEFAULT_MAX_ERROR_DEG: f64 = 1e-3;

/// What to export.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportRequest {
    /// calibration.json.
    pub calibration: PathBuf,
    /// The format.
    pub target: ExportTarget,
    /// Pixel pitch, µm.
    pub pixel_um: f64,
    /// Largest angle error accepted, degrees.
    pub max_error_deg: f64,
    /// The file to write.
    pub out: PathBuf,
    /// Bounds on the files read whole (docs/formats.md, "Limits").
    pub limits: psdcal_io::ReadLimits,
}

/// The written model and its error.
#[derive(Debug, Clone, PartialEq)]
pub struct Exported {
    /// The request.
    pub request: ExportRequest,
    /// The fit written.
    pub fit: CameraFit,
    /// The file's numbers (pixels).
    pub file: CameraModelFile,
    /// ROS only: the 5-coefficient fit's largest angle error when it was
    /// not good enough.
    pub plumb_bob_max_deg: Option<f64>,
    /// What the exported model leaves out.
    pub warnings: Vec<String>,
}

/// Image size in pixels of a side of `side_mm` at `pitch_um`, when whole.
fn pixels(side_mm: f64, pitch_um: f64) -> Result<u64> {
    let n = 1000.0 * side_mm / pitch_um;
    let whole = n.round();
    if !(1.0..=1e8).contains(&whole) || (n - whole).abs() > 1e-6 * n.max(1.0) {
        return Err(Error::Options(format!(
            "--pixel-um {pitch_um}: a {side_mm} mm side is {n} pixels, not a whole number from 1 \
             to 1e8; choose a pitch that divides the side (e.g. 1, 2.5 or 4.5 µm for 9 mm)"
        )));
    }
    Ok(whole as u64)
}

/// What of the calibration OpenCV's model cannot follow (for messages).
fn unrepresentable_parts(loaded: &LoadedSensor) -> Vec<String> {
    let s = &loaded.sensor;
    let (i, d) = (&s.model.intrinsics, &s.model.distortion);
    let mut parts = Vec::new();
    if let Some(map) = &s.psd_map {
        parts.push(format!(
            "its PSD map ({}) is a non-radial displacement field",
            map.stage.basis().label()
        ));
    }
    if (d.l1 != 0.0 || d.l2 != 0.0) && (i.cx != 0.0 || i.cy != 0.0) {
        parts.push(
            "its PSD radial distortion (l1, l2) is centred on the electrical centre, not on the \
             optical centre"
                .into(),
        );
    }
    if i.skew != 0.0 {
        parts.push("its skew is not in OpenCV's distortion model".into());
    }
    parts
}

/// Reads the calibration, fits, checks the error and writes the file.
pub fn export(request: &ExportRequest) -> Result<Exported> {
    for (name, v) in [
        ("--pixel-um", request.pixel_um),
        ("--max-error-deg", request.max_error_deg),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::Options(format!(
                "{name} {v}: expected a positive number"
            )));
        }
    }
    let loaded = LoadedSensor::read_with(&request.calibration, request.limits)?;
    let g = loaded.sensor.geometry;
    let (width, height) = (
        pixels(g.lx, request.pixel_um)?,
        pixels(g.ly, request.pixel_um)?,
    );
    let options = CameraFitOptions::default();
    let mut plumb_bob_max_deg = None;
    let fit = if request.target == ExportTarget::Ros {
        let five = fit_opencv(&loaded.sensor, OpenCvKind::Five, &options)?;
        if five.unanswered == 0 && five.max_deg <= request.max_error_deg {
            five
        } else {
            plumb_bob_max_deg = Some(five.max_deg);
            fit_opencv(&loaded.sensor, OpenCvKind::Rational, &options)?
        }
    } else {
        fit_opencv(&loaded.sensor, OpenCvKind::Rational, &options)?
    };
    if fit.unanswered > 0 || fit.max_deg > request.max_error_deg {
        let mut why = unrepresentable_parts(&loaded);
        if why.is_empty() {
            why.push("its correction's shape is beyond the 8-coefficient rational model".into());
        }
        let error = if fit.unanswered > 0 {
            format!(
                "the fitted model has no ray at {} of {} points",
                fit.unanswered, fit.checked_points
            )
        } else {
            format!(
                "the fitted model's angles differ from psdcal's by up to {:.3e}° (at {:.2}, {:.2} \
                 mm)",
                fit.max_deg, fit.worst_at_mm.x, fit.worst_at_mm.y
            )
        };
        return Err(Error::Input(format!(
            "{}: not exported to {}: OpenCV's rational model cannot represent this calibration: \
             {}; {error}, above --max-error-deg {}. Raise --max-error-deg to write it anyway",
            request.calibration.display(),
            request.target.name(),
            why.join("; "),
            request.max_error_deg
        )));
    }
    let mut warnings = Vec::new();
    if let Some(gains) = loaded.sensor.gains.filter(|g| g.to_array() != [1.0; 3]) {
        warnings.push(format!(
            "the channel gains (g_x2 {}, g_y1 {}, g_y2 {}) act on the electrode amplitudes \
             before the point and are not in the exported model: compute points from amplitudes \
             with the gains divided out (docs/model.md §1.3)",
            gains.x2, gains.y1, gains.y2
        ));
    }
    if !loaded.sensor.valid_region.whole_active_area() {
        warnings.push(
            "the calibration's valid region does not cover the whole active area: the exported \
             model also answers points outside it, which psdcal refuses"
                .into(),
        );
    }
    for part in unrepresentable_parts(&loaded) {
        warnings.push(format!("{part}: approximated within {:.3e}°", fit.max_deg));
    }
    let scale = 1000.0 / request.pixel_um;
    let p = &fit.model.params;
    let camera = [
        scale * p[0],
        scale * p[1],
        scale * (p[2] + g.lx / 2.0) - 0.5,
        scale * (p[3] + g.ly / 2.0) - 0.5,
    ];
    let distortion = match fit.kind {
        OpenCvKind::Five => p[4..9].to_vec(),
        OpenCvKind::Rational => p[4..].to_vec(),
    };
    let mut exported = Exported {
        request: request.clone(),
        fit,
        file: CameraModelFile {
            width_px: width,
            height_px: height,
            camera,
            distortion,
            comments: Vec::new(),
        },
        plumb_bob_max_deg,
        warnings,
    };
    exported.file.comments = exported.comments();
    let format = match request.target {
        ExportTarget::OpenCv => CameraFormat::OpenCv,
        ExportTarget::Mrcal => CameraFormat::Mrcal,
        ExportTarget::Ros => CameraFormat::Ros,
    };
    write_camera_model(&request.out, &exported.file, format)?;
    Ok(exported)
}

impl Exported {
    fn model_name(&self) -> &'static str {
        match (self.fit.kind, self.request.target) {
            (OpenCvKind::Five, _) => "plumb_bob (k1, k2, p1, p2, k3)",
            (OpenCvKind::Rational, ExportTarget::Mrcal) => "LENSMODEL_OPENCV8",
            (OpenCvKind::Rational, ExportTarget::Ros) => "rational_polynomial",
            (OpenCvKind::Rational, ExportTarget::OpenCv) => {
                "rational (k1, k2, p1, p2, k3, k4, k5, k6)"
            }
        }
    }

    fn error_line(&self) -> String {
        let f = &self.fit;
        format!(
            "conversion error over the valid region ({} points): point RMS {:.3e} um, max {:.3e} \
             um; angle RMS {:.3e} deg, max {:.3e} deg (at {:.3}, {:.3} mm)",
            f.checked_points,
            f.rms_um,
            f.max_um,
            f.rms_deg,
            f.max_deg,
            f.worst_at_mm.x,
            f.worst_at_mm.y
        )
    }

    /// The comment lines the file starts with (ASCII).
    fn comments(&self) -> Vec<String> {
        let name = self
            .request
            .calibration
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let p = self.request.pixel_um;
        let g = (
            self.file.width_px as f64 * p / 1000.0,
            self.file.height_px as f64 * p / 1000.0,
        );
        let mut lines = vec![
            format!(
                "psdcal export of {name}: OpenCV camera model {}",
                self.model_name()
            ),
            format!(
                "pixels: pitch {p} um, image {} x {}; the sensor point (x_mm, y_mm) is the pixel \
                 u = 1000 (x_mm + Lx/2)/{p} - 0.5, v = 1000 (y_mm + Ly/2)/{p} - 0.5 (no flip; \
                 Lx = {} mm, Ly = {} mm)",
                self.file.width_px, self.file.height_px, g.0, g.1
            ),
            "the ray of a pixel is psdcal's: alpha_x = atan(x'), alpha_y = atan(y') of the \
             undistorted normalised point (x', y')"
                .into(),
            self.error_line(),
        ];
        if let Some(max) = self.plumb_bob_max_deg {
            lines.push(format!(
                "plumb_bob was not used: its angle error reaches {max:.3e} deg"
            ));
        }
        lines.extend(self.warnings.iter().map(|w| format!("warning: {w}")));
        lines
    }

    /// The text summary.
    pub fn summary(&self) -> String {
        let mut text = format!(
            "wrote {} ({}, {}): {} x {} pixels of {} µm\n{}",
            self.request.out.display(),
            self.request.target.name(),
            self.model_name(),
            self.file.width_px,
            self.file.height_px,
            self.request.pixel_um,
            self.error_line().replace(" um", " µm").replace(" deg", "°")
        );
        if let Some(max) = self.plumb_bob_max_deg {
            text += &format!("\nplumb_bob was not used: its angle error reaches {max:.3e}°");
        }
        text
    }

    /// The JSON summary.
    pub fn to_json(&self) -> serde_json::Value {
        let f = &self.fit;
        let names = match f.kind {
            OpenCvKind::Five => &OPENCV8_NAMES[4..9],
            OpenCvKind::Rational => &OPENCV8_NAMES[4..],
        };
        let distortion: serde_json::Map<String, serde_json::Value> = names
            .iter()
            .zip(&self.file.distortion)
            .map(|(n, v)| (n.to_string(), json!(v)))
            .collect();
        let [fx, fy, cx, cy] = self.file.camera;
        json!({
            "calibration": self.request.calibration.display().to_string(),
            "out": self.request.out.display().to_string(),
            "to": self.request.target.name(),
            "model": match f.kind { OpenCvKind::Five => "plumb_bob", OpenCvKind::Rational => "rational" },
            "pixel_um": self.request.pixel_um,
            "image_px": [self.file.width_px, self.file.height_px],
            "camera_px": {"fx": fx, "fy": fy, "cx": cx, "cy": cy},
            "distortion": distortion,
            "error": {
                "points_fitted": f.fitted_points,
                "points_checked": f.checked_points,
                "rms_um": f.rms_um,
                "max_um": f.max_um,
                "rms_deg": f.rms_deg,
                "max_deg": f.max_deg,
                "worst_at_mm": [f.worst_at_mm.x, f.worst_at_mm.y],
            },
            "plumb_bob_max_deg": self.plumb_bob_max_deg,
            "max_error_deg": self.request.max_error_deg,
            "warnings": self.warnings,
        })
    }
}
