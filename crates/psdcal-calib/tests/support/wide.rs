//! Judging the calibration's global search over `l1` on wide scenarios
//! (`psdcal_testkit::wide`), against fits started from the truth.
//!
//! For one scenario:
//! - (a) the automatic calibration, `calibrate` with `f, cx, cy, k1, k2, l1`
//!   freed (what `psdcal calibrate --fit f,cx,cy,k1,k2,l1` runs; default
//!   options otherwise);
//! - (b) the reference: `refine` started from the truth (model and poses)
//!   with `l1` held at its true value and `f, cx, cy, k1, k2` freed;
//! - (c) `refine` from the truth with `l1` freed too.
//!
//! The verdict: (a)'s cost must not exceed (b)'s. Since (b) is a point of
//! the cost with `l1` at one value, the global minimum over `l1` is at or
//! below it, so a fit above it has stopped in a wrong minimum, whatever the
//! noise. Tolerance: 1e-6 relative (the solver stops when a step lowers the
//! cost by less than 1e-10 of it; 1e-6 is far above the two fits' stopping
//! differences) plus 1e-18 mm² per point (a hundred times the exact-fit
//! threshold of the refinement, mean 1e-20 mm² per point), for noise-free
//! data where both costs are rounding.

use std::time::{Duration, Instant};

use psdcal_calib::{
    calibrate, refine, CalibrateOptions, CalibrationData, ImageObservations, Observation,
    RefineOptions,
};
use psdcal_model::{Param, PsdGeometry};
use psdcal_testkit::WideScenario;

/// Relative tolerance of the verdict.
pub const RELATIVE_TOLERANCE: f64 = 1e-6;

/// Absolute tolerance of the verdict per point, mm².
pub const ABSOLUTE_TOLERANCE_PER_POINT: f64 = 1e-18;

/// The scenario's points as `CalibrationData` (images named 1, 2, …, only
/// the LEDs each image kept, a 9 × 9 mm PSD, no declared lines).
pub fn data(s: &WideScenario) -> CalibrationData {
    let images = s
        .images
        .iter()
        .enumerate()
        .map(|(i, image)| ImageObservations {
            id: format!("{}", i + 1),
            points: image
                .points
                .iter()
                .map(|&(led, measured)| Observation { led, measured })
                .collect(),
        })
        .collect();
    CalibrationData {
        template: s.template.clone(),
        lines: Vec::new(),
        images,
        geometry: PsdGeometry::default(),
        amplitudes: None,
        noise_scale: None,
    }
}

/// The freed parameters of the free-`l1` fits.
pub fn free_with_l1() -> Vec<Param> {
    vec![
        Param::F,
        Param::Cx,
        Param::Cy,
        Param::K1,
        Param::K2,
        Param::L1,
    ]
}

/// What one fit reached.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    /// Its cost, mm² (template plane).
    pub cost: f64,
    /// Its focal length, mm.
    pub f: f64,
    /// Its optical centre, mm.
    pub cx: f64,
    /// Its optical centre, mm.
    pub cy: f64,
    /// Its lens `k1`, mm⁻².
    pub k1: f64,
    /// Its PSD `l1`, mm⁻².
    pub l1: f64,
}

impl Fit {
    fn of(cost: f64, model: &psdcal_model::Model) -> Self {
        let s = model.sensor_model();
        Self {
            cost,
            f: s.intrinsics.f,
            cx: s.intrinsics.cx,
            cy: s.intrinsics.cy,
            k1: s.distortion.k1,
            l1: s.distortion.l1,
        }
    }
}

/// The judgement of one scenario.
#[derive(Debug, Clone)]
pub struct Verdict {
    /// The scenario's index.
    pub index: u64,
    /// Lens 1 or 2.
    pub lens: u8,
    /// Its true `l1`, mm⁻².
    pub l1_true: f64,
    /// Its σ, mm.
    pub sigma_mm: f64,
    /// Images and points.
    pub images: usize,
    /// Points.
    pub points: usize,
    /// (a) the automatic calibration, or why it failed.
    pub automatic: Result<Fit, String>,
    /// (a)'s reported standard deviation of `l1`.
    pub l1_std: Option<f64>,
    /// (a)'s number of distinct minima found by the global search.
    pub minima: usize,
    /// (b) from the truth, `l1` held at its true value.
    pub fixed_at_truth: Result<Fit, String>,
    /// (c) from the truth, `l1` freed.
    pub free_from_truth: Result<Fit, String>,
    /// The true optical centre, mm.
    pub centre_true: (f64, f64),
    /// The true focal length, mm.
    pub f_true: f64,
    /// Wall-clock time of (a) (reported, never judged).
    pub elapsed: Duration,
}

impl Verdict {
    /// The verdict's tolerance on (b)'s cost, mm².
    pub fn allowance(&self) -> f64 {
        let reference = self.fixed_at_truth.as_ref().map_or(0.0, |b| b.cost);
        RELATIVE_TOLERANCE * reference + ABSOLUTE_TOLERANCE_PER_POINT * self.points as f64
    }

    /// Whether the automatic fit ended at or below the cost of the fit with
    /// `l1` held at its true value (the acceptance criterion). A failed
    /// calibration fails; a failed reference cannot judge (then `true` only
    /// if the calibration succeeded).
    pub fn passes(&self) -> bool {
        match (&self.automatic, &self.fixed_at_truth) {
            (Ok(a), Ok(b)) => a.cost <= b.cost + self.allowance(),
            (Ok(_), Err(_)) => true,
            (Err(_), _) => false,
        }
    }

    /// (a)'s cost over (b)'s (`NaN` when either failed).
    pub fn cost_ratio(&self) -> f64 {
        match (&self.automatic, &self.fixed_at_truth) {
            (Ok(a), Ok(b)) => a.cost / b.cost,
            _ => f64::NAN,
        }
    }

    /// (a)'s `l1` minus the truth's, mm⁻².
    pub fn l1_error(&self) -> f64 {
        self.automatic
            .as_ref()
            .map_or(f64::NAN, |a| a.l1 - self.l1_true)
    }

    /// Distance of (a)'s optical centre from the truth's, mm.
    pub fn centre_error(&self) -> f64 {
        self.automatic.as_ref().map_or(f64::NAN, |a| {
            (a.cx - self.centre_true.0).hypot(a.cy - self.centre_true.1)
        })
    }

    /// Whether (a) and (c) reached the same minimum: costs within the
    /// verdict's tolerance and `l1` within a tenth of (a)'s σ (at least
    /// 1e-7 mm⁻²). `None` when either failed.
    pub fn same_as_truth_start(&self) -> Option<bool> {
        let (a, c) = (
            self.automatic.as_ref().ok()?,
            self.free_from_truth.as_ref().ok()?,
        );
        let cost_tol = RELATIVE_TOLERANCE * a.cost.max(c.cost)
            + ABSOLUTE_TOLERANCE_PER_POINT * self.points as f64;
        let l1_tol = (0.1 * self.l1_std.unwrap_or(0.0)).max(1e-7);
        Some((a.cost - c.cost).abs() <= cost_tol && (a.l1 - c.l1).abs() <= l1_tol)
    }

    /// The CSV header of [`Self::csv_row`].
    pub const CSV_HEADER: &'static str = "index,lens,f_true,l1_true,sigma_mm,images,points,\
status,pass,cost_auto,cost_l1_fixed_truth,cost_l1_free_truth,cost_ratio,l1_auto,l1_std_auto,\
l1_free_truth,l1_error,centre_error_mm,f_error_mm,same_as_truth_start,minima,error";

    /// One CSV row (no timing: the file is the same whatever the threads).
    pub fn csv_row(&self) -> String {
        let cost = |r: &Result<Fit, String>| {
            r.as_ref()
                .map_or(String::new(), |f| format!("{:e}", f.cost))
        };
        let (status, error) = match (&self.automatic, &self.fixed_at_truth) {
            (Err(e), _) => ("calibrate_failed", e.clone()),
            (Ok(_), Err(e)) => ("reference_failed", e.clone()),
            _ => ("ok", String::new()),
        };
        let auto = self.automatic.as_ref().ok();
        format!(
            "{},{},{},{:e},{:e},{},{},{},{},{},{},{},{:e},{},{},{},{:e},{:e},{},{},{},\"{}\"",
            self.index,
            self.lens,
            self.f_true,
            self.l1_true,
            self.sigma_mm,
            self.images,
            self.points,
            status,
            self.passes(),
            cost(&self.automatic),
            cost(&self.fixed_at_truth),
            cost(&self.free_from_truth),
            self.cost_ratio(),
            auto.map_or(String::new(), |a| format!("{:e}", a.l1)),
            self.l1_std.map_or(String::new(), |s| format!("{s:e}")),
            self.free_from_truth
                .as_ref()
                .map_or(String::new(), |c| format!("{:e}", c.l1)),
            self.l1_error(),
            self.centre_error(),
            auto.map_or(String::new(), |a| format!("{:e}", a.f - self.f_true)),
            self.same_as_truth_start()
                .map_or(String::new(), |b| b.to_string()),
            self.minima,
            error.replace('"', "'"),
        )
    }
}

/// Judges scenario `s` (module documentation).
pub fn judge(s: &WideScenario) -> Verdict {
    let data = data(s);
    let truth_poses = s.poses();
    let with_l1 = RefineOptions {
        free: free_with_l1(),
        ..RefineOptions::default()
    };
    let options = CalibrateOptions {
        refine: with_l1.clone(),
        ..CalibrateOptions::default()
    };
    let clock = Instant::now();
    let result = calibrate(&data, &options);
    let elapsed = clock.elapsed();
    let (automatic, l1_std, minima) = match &result {
        Ok(r) => (
            Ok(Fit::of(r.cost, &r.model)),
            r.covariance.std("l1"),
            r.global.as_ref().map_or(0, |g| g.minima.len()),
        ),
        Err(e) => (Err(e.to_string()), None, 0),
    };
    let from_truth = |options: &RefineOptions| {
        refine(&data, s.truth, &truth_poses, options)
            .map(|r| Fit::of(r.cost, &r.model))
            .map_err(|e| e.to_string())
    };
    let fixed_at_truth = from_truth(&RefineOptions::default());
    let free_from_truth = from_truth(&with_l1);
    Verdict {
        index: s.index,
        lens: s.lens.number(),
        l1_true: s.truth.distortion.l1,
        sigma_mm: s.sigma_mm,
        images: s.images.len(),
        points: s.point_count(),
        automatic,
        l1_std,
        minima,
        fixed_at_truth,
        free_from_truth,
        centre_true: (s.truth.intrinsics.cx, s.truth.intrinsics.cy),
        f_true: s.truth.intrinsics.f,
        elapsed,
    }
}
