//! Camera models for other tools (docs/formats.md, "Exported camera
//! models"): OpenCV's FileStorage YAML, mrcal's `.cameramodel` and ROS's
//! `camera_info` YAML, written from plain numbers in pixels.
//!
//! Every file starts with `#` comment lines (the pixel convention and the
//! conversion's error, given by the caller). Numbers are written so that
//! every reader takes them as floats: with a decimal point and, in
//! scientific notation, a signed exponent (`1.5e-05`), which YAML 1.1
//! readers such as PyYAML need; a value read back is the same `f64`.

use std::io::Write as _;
use std::path::Path;

use crate::atomic::write_atomic;
use crate::IoError;

/// The three formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CameraFormat {
    /// OpenCV FileStorage YAML (`camera_matrix`, `distortion_coefficients`).
    OpenCv,
    /// mrcal `.cameramodel` (`LENSMODEL_OPENCV8`, or `OPENCV5` for 5
    /// coefficients; extrinsics the identity).
    Mrcal,
    /// ROS `camera_info` YAML (`plumb_bob` for 5 coefficients,
    /// `rational_polynomial` for 8).
    Ros,
}

/// A pinhole camera with OpenCV's distortion, in pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraModelFile {
    /// Image width, pixels.
    pub width_px: u64,
    /// Image height, pixels.
    pub height_px: u64,
    /// `fx, fy, cx, cy`, pixels.
    pub camera: [f64; 4],
    /// OpenCV's distortion vector `k1, k2, p1, p2, k3[, k4, k5, k6]`.
    pub distortion: Vec<f64>,
    /// Comment lines written first (without `#`).
    pub comments: Vec<String>,
}

/// `v` as text every YAML and Python reader takes as the same float.
pub fn float_text(v: f64) -> String {
    let plain = v.to_string();
    if v == 0.0 || (1e-4..1e15).contains(&v.abs()) {
        return if plain.contains('.') {
            plain
        } else {
            format!("{plain}.0")
        };
    }
    let s = format!("{v:e}");
    let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
    let mantissa = if mantissa.contains('.') {
        mantissa.to_string()
    } else {
        format!("{mantissa}.0")
    };
    let exponent = exponent.parse::<i32>().unwrap_or(0);
    format!("{mantissa}e{exponent:+03}")
}

fn list(values: &[f64]) -> String {
    let items: Vec<String> = values.iter().map(|v| float_text(*v)).collect();
    format!("[{}]", items.join(", "))
}

impl CameraModelFile {
    fn check(&self) -> Result<(), String> {
        if ![5, 8].contains(&self.distortion.len()) {
            return Err(format!(
                "{} distortion coefficients; expected 5 or 8",
                self.distortion.len()
            ));
        }
        if self
            .camera
            .iter()
            .chain(&self.distortion)
            .any(|v| !v.is_finite())
        {
            return Err("a non-finite number".into());
        }
        if self.width_px == 0 || self.height_px == 0 {
            return Err("an empty image".into());
        }
        Ok(())
    }

    fn comment_lines(&self, out: &mut String) {
        for comment in &self.comments {
            for line in comment.lines() {
                out.push_str(&format!("# {line}\n"));
            }
        }
    }

    /// The file's text in `format`.
    pub fn text(&self, format: CameraFormat) -> String {
        let [fx, fy, cx, cy] = self.camera;
        let matrix = list(&[fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0]);
        let n = self.distortion.len();
        let mut out = String::new();
        match format {
            CameraFormat::OpenCv => {
                out.push_str("%YAML:1.0\n---\n");
                self.comment_lines(&mut out);
                out.push_str(&format!(
                    "image_width: {}\nimage_height: {}\n",
                    self.width_px, self.height_px
                ));
                out.push_str(&format!(
                    "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: {matrix}\n"
                ));
                out.push_str(&format!(
                    "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: {n}\n   dt: d\n   data: {}\n",
                    list(&self.distortion)
                ));
            }
            CameraFormat::Mrcal => {
                self.comment_lines(&mut out);
                let model = if n == 8 { "OPENCV8" } else { "OPENCV5" };
                let mut intrinsics = vec![fx, fy, cx, cy];
                intrinsics.extend(&self.distortion);
                out.push_str(&format!("{{\n    'lensmodel': 'LENSMODEL_{model}',\n"));
                out.push_str(
                    "    # intrinsics are fx, fy, cx, cy, k1, k2, p1, p2, k3[, k4, k5, k6]\n",
                );
                out.push_str(&format!("    'intrinsics': {},\n", list(&intrinsics)));
                out.push_str("    # extrinsics are rt_fromref: the sensor is the reference\n");
                out.push_str("    'extrinsics': [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],\n");
                out.push_str(&format!(
                    "    'imagersize': [{}, {}],\n}}\n",
                    self.width_px, self.height_px
                ));
            }
            CameraFormat::Ros => {
                self.comment_lines(&mut out);
                let model = if n == 8 {
                    "rational_polynomial"
                } else {
                    "plumb_bob"
                };
                out.push_str(&format!(
                    "image_width: {}\nimage_height: {}\ncamera_name: psdcal\n",
                    self.width_px, self.height_px
                ));
                out.push_str(&format!(
                    "camera_matrix:\n  rows: 3\n  cols: 3\n  data: {matrix}\n"
                ));
                out.push_str(&format!("distortion_model: {model}\n"));
                out.push_str(&format!(
                    "distortion_coefficients:\n  rows: 1\n  cols: {n}\n  data: {}\n",
                    list(&self.distortion)
                ));
                out.push_str(&format!(
                    "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: {}\n",
                    list(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
                ));
                out.push_str(&format!(
                    "projection_matrix:\n  rows: 3\n  cols: 4\n  data: {}\n",
                    list(&[fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0])
                ));
            }
        }
        out
    }
}

/// Writes `model` to `path` in `format`, atomically.
pub fn write_camera_model(
    path: &Path,
    model: &CameraModelFile,
    format: CameraFormat,
) -> Result<(), IoError> {
    model.check().map_err(|reason| IoError::Write {
        file: path.display().to_string(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, reason),
    })?;
    let text = model.text(format);
    write_atomic(path, |w| w.write_all(text.as_bytes()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_read_back_exactly_and_look_like_floats() {
        for v in [
            0.0,
            1.0,
            -2.5,
            9000.0,
            1e-5,
            -3.25e-12,
            1.234_567_890_123_4e20,
            0.1 + 0.2,
        ] {
            let s = float_text(v);
            assert!(s.contains('.'), "{s}");
            if let Some((_, e)) = s.split_once('e') {
                assert!(e.starts_with('+') || e.starts_with('-'), "{s}");
            }
            assert_eq!(s.parse::<f64>().unwrap(), v, "{s}");
        }
    }

    #[test]
    fn each_format_has_its_keys() {
        let model = CameraModelFile {
            width_px: 9000,
            height_px: 9000,
            camera: [8000.0, 8000.0, 4999.5, 3799.5],
            distortion: vec![0.1, -0.2, 1e-6, 2e-6, 0.3],
            comments: vec!["first\nsecond".into()],
        };
        let ros = model.text(CameraFormat::Ros);
        assert!(ros.starts_with("# first\n# second\n"));
        assert!(ros.contains("distortion_model: plumb_bob"));
        let opencv = model.text(CameraFormat::OpenCv);
        assert!(opencv.starts_with("%YAML:1.0\n---\n# first"));
        assert!(opencv.contains("cols: 5"));
        let mrcal = model.text(CameraFormat::Mrcal);
        assert!(
            mrcal.contains("'LENSMODEL_OPENCV5'") && mrcal.contains("'imagersize': [9000, 9000]")
        );
    }
}
