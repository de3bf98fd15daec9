//! A tracking filter over the windows' positions (docs/model.md §9): per
//! LED, a constant-velocity Kalman filter in the world frame.
//!
//! # Equations
//!
//! State `x = (p, v)` (position mm, velocity mm/s, world frame), covariance
//! `P` (6×6). Between two windows `Δt` apart the LED moves with constant
//! velocity disturbed by a continuous white acceleration of spectral density
//! `q = σ_a² · 1 s` per axis (`σ_a` = `--accel-sigma`, mm/s²; the velocity
//! wanders by `σ_a √(Δt / 1 s)` over `Δt`):
//!
//! ```text
//! F = [I  Δt I]      Q = q [Δt³/3 I   Δt²/2 I]
//!     [0     I]            [Δt²/2 I   Δt    I]
//! x⁻ = F x,   P⁻ = F P Fᵀ + Q                       (prediction)
//! ```
//!
//! `Q` is the exact discretisation of the continuous model
//! (`∫₀^Δt e^{Aτ} G q Gᵀ e^{Aᵀτ} dτ`). The measurement is the window's
//! intersection `z` with its covariance `R` (3×3), `H = [I 0]`:
//!
//! ```text
//! ν = z − H x⁻,   S = H P⁻ Hᵀ + R,   d² = νᵀ S⁻¹ ν      (innovation, gate)
//! K = P⁻ Hᵀ S⁻¹,  x = x⁻ + K ν,  P = (I − K H) P⁻ (I − K H)ᵀ + K R Kᵀ   (Joseph form)
//! ```
//!
//! **Gating**: a measurement with `d²` beyond the gate
//! ([`CvOptions::gate_d2`], χ²₃'s 0.9999 quantile 21.1) is an outlier: not
//! used, the window answered by the prediction (`gated`). **Loss and
//! re-initialisation**: after [`CvOptions::max_missed`] windows in a row
//! without a used measurement (dark, gated or no fix), or a gap of more than
//! [`CvOptions::max_gap_s`] between windows, the track is dropped; the next
//! measurement starts it again: `p = z`, `P_pp = R`, `v = 0`,
//! `P_vv = σ_v0² I` ([`CvOptions::initial_speed_sigma_mm_s`]).
//!
//! **Consistency**: with the model true, the normalised estimation error
//! squared `(p − p_true)ᵀ P_pp⁻¹ (p − p_true)` is χ² with 3 degrees of
//! freedom (mean 3); the tests check it by Monte Carlo.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// The filter's options (module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CvOptions {
    /// `σ_a`, mm/s²: the white acceleration's spectral density is
    /// `σ_a² · 1 s` per axis.
    pub accel_sigma_mm_s2: f64,
    /// The gate on `d²`: an innovation beyond it is an outlier
    /// ([`GATE_D2_9999`]: χ²₃'s 0.9999 quantile).
    pub gate_d2: f64,
    /// Windows in a row without a used measurement before the track is
    /// dropped.
    pub max_missed: usize,
    /// A gap between two windows longer than this drops the track, s.
    pub max_gap_s: f64,
    /// The velocity's prior σ per axis when a track starts, mm/s.
    pub initial_speed_sigma_mm_s: f64,
}

/// The default `σ_a`, mm/s²: people and robots walking at up to 1 m/s
/// change their velocity by a few tenths of a metre per second within a
/// second (starting, stopping and turning take one to a few seconds; a
/// 1 m/s walk around a 1 m radius turn is 1 m/s²), so the velocity's random
/// walk is given σ = 0.4 m/s over 1 s. On the simulated walk of
/// `simulate-positioning --moving` (turns at 1 m/s², stops) the filtered
/// position error is lowest for 300–500 mm/s² (0.73–0.79× the windows'),
/// and the NEES stays consistent from 200 to 1 000 mm/s².
pub const DEFAULT_ACCEL_SIGMA_MM_S2: f64 = 400.0;

/// The 0.9999 quantile of χ² with 3 degrees of freedom: `d²` beyond it
/// happens once in 10 000 consistent updates.
pub const GATE_D2_9999: f64 = 21.107_513_738_5;

impl Default for CvOptions {
    fn default() -> Self {
        Self {
            accel_sigma_mm_s2: DEFAULT_ACCEL_SIGMA_MM_S2,
            gate_d2: GATE_D2_9999,
            max_missed: 10,
            max_gap_s: 1.0,
            initial_speed_sigma_mm_s: 1500.0,
        }
    }
}

/// The tracking filter of `track` and `serve` (the option concept).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[non_exhaustive]
pub enum TrackFilter {
    /// Per-window intersections, unfiltered.
    #[default]
    None,
    /// A constant-velocity Kalman filter per LED.
    ConstantVelocity(CvOptions),
}

impl TrackFilter {
    /// Its name (`none`, `cv`).
    pub fn name(&self) -> &'static str {
        match self {
            TrackFilter::None => "none",
            TrackFilter::ConstantVelocity(_) => "cv",
        }
    }

    /// The filter named `name` (`none`, `cv`; case ignored) with the
    /// white acceleration `accel_sigma_mm_s2` (the default when `None`).
    /// Refusals name what was expected.
    pub fn from_name(name: &str, accel_sigma_mm_s2: Option<f64>) -> Result<Self, String> {
        let filter = match name.trim().to_ascii_lowercase().as_str() {
            "none" => TrackFilter::None,
            "cv" => {
                let mut options = CvOptions::default();
                if let Some(a) = accel_sigma_mm_s2 {
                    if !(a.is_finite() && a > 0.0) {
                        return Err(format!(
                            "--accel-sigma {a}: expected a finite, positive acceleration, mm/s²"
                        ));
                    }
                    options.accel_sigma_mm_s2 = a;
                }
                TrackFilter::ConstantVelocity(options)
            }
            other => {
                return Err(format!(
                    "unknown filter '{other}'; expected one of none, cv"
                ))
            }
        };
        if filter == TrackFilter::None && accel_sigma_mm_s2.is_some() {
            return Err("--accel-sigma belongs to --filter cv; expected --filter cv".to_string());
        }
        Ok(filter)
    }
}

/// What became of a window's measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FilterStep {
    /// The track started (again) from this measurement.
    Started,
    /// The measurement was used.
    Updated,
    /// The measurement was an outlier (beyond the gate): the prediction.
    Gated,
    /// No measurement: the prediction.
    Predicted,
    /// No track (never started, or dropped).
    Lost,
}

impl FilterStep {
    /// The status word of a row answered by the prediction (`gated`,
    /// `predicted`), or `None` when the measurement's own status stands.
    pub fn status(self) -> Option<&'static str> {
        match self {
            FilterStep::Gated => Some("gated"),
            FilterStep::Predicted => Some("predicted"),
            _ => None,
        }
    }
}

/// The filter's state of one LED.
#[derive(Debug, Clone, PartialEq)]
pub struct CvState {
    /// `(p, v)`: mm and mm/s, world frame.
    pub x: Vector6<f64>,
    /// Its covariance.
    pub p: Matrix6<f64>,
    /// Time of the state, s.
    pub t_s: f64,
}

impl CvState {
    /// The position, mm.
    pub fn position(&self) -> Vector3<f64> {
        self.x.fixed_rows::<3>(0).into_owned()
    }

    /// The velocity, mm/s.
    pub fn velocity(&self) -> Vector3<f64> {
        self.x.fixed_rows::<3>(3).into_owned()
    }

    /// The position's covariance, mm².
    pub fn position_covariance(&self) -> Matrix3<f64> {
        self.p.fixed_view::<3, 3>(0, 0).into_owned()
    }
}

/// A constant-velocity Kalman filter of one LED (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct CvFilter {
    options: CvOptions,
    state: Option<CvState>,
    missed: usize,
}

/// `F(Δt)` and `Q(Δt)` for the spectral density `q` (module documentation).
pub fn transition(dt: f64, q: f64) -> (Matrix6<f64>, Matrix6<f64>) {
    let mut f = Matrix6::identity();
    let mut qm = Matrix6::zeros();
    for i in 0..3 {
        f[(i, i + 3)] = dt;
        qm[(i, i)] = q * dt.powi(3) / 3.0;
        qm[(i, i + 3)] = q * dt * dt / 2.0;
        qm[(i + 3, i)] = q * dt * dt / 2.0;
        qm[(i + 3, i + 3)] = q * dt;
    }
    (f, qm)
}

impl CvFilter {
    /// A filter without a track yet.
    pub fn new(options: CvOptions) -> Self {
        Self {
            options,
            state: None,
            missed: 0,
        }
    }

    /// The current state (`None`: no track).
    pub fn state(&self) -> Option<&CvState> {
        self.state.as_ref()
    }

    /// Starts the track at `state` (a prior of the caller's).
    pub fn start_from(&mut self, state: CvState) {
        self.state = Some(state);
        self.missed = 0;
    }

    /// The window at `t_s` with its measurement (`z`, `R`) or none: predicts
    /// to `t_s`, then updates, gates or starts (module documentation). A
    /// measurement whose `R` is not symmetric positive definite or not
    /// finite counts as none.
    pub fn step(
        &mut self,
        t_s: f64,
        measurement: Option<(Vector3<f64>, Matrix3<f64>)>,
    ) -> FilterStep {
        let measurement = measurement.filter(|(z, r)| {
            z.iter().all(|v| v.is_finite())
                && r.iter().all(|v| v.is_finite())
                && r.cholesky().is_some()
        });
        if let Some(state) = &self.state {
            let dt = t_s - state.t_s;
            if !(dt.is_finite() && dt >= 0.0 && dt <= self.options.max_gap_s) {
                self.state = None;
            }
        }
        let Some(state) = self.state.as_mut() else {
            return match measurement {
                Some((z, r)) => {
                    self.state = Some(self.started(t_s, z, r));
                    self.missed = 0;
                    FilterStep::Started
                }
                None => FilterStep::Lost,
            };
        };
        let q = self.options.accel_sigma_mm_s2.powi(2);
        let (f, qm) = transition(t_s - state.t_s, q);
        state.x = f * state.x;
        state.p = f * state.p * f.transpose() + qm;
        state.p = (state.p + state.p.transpose()) * 0.5;
        state.t_s = t_s;
        let used = measurement.and_then(|(z, r)| update(state, &z, &r, self.options.gate_d2));
        match (measurement, used) {
            (_, Some(())) => {
                self.missed = 0;
                FilterStep::Updated
            }
            (m, None) => {
                self.missed += 1;
                if self.missed > self.options.max_missed {
                    self.state = None;
                    // A measurement that failed the gate of a lost track
                    // starts the new one.
                    if let Some((z, r)) = m {
                        self.state = Some(self.started(t_s, z, r));
                        self.missed = 0;
                        return FilterStep::Started;
                    }
                    return FilterStep::Lost;
                }
                if m.is_some() {
                    FilterStep::Gated
                } else {
                    FilterStep::Predicted
                }
            }
        }
    }

    /// A new track at `z` (module documentation).
    fn started(&self, t_s: f64, z: Vector3<f64>, r: Matrix3<f64>) -> CvState {
        let mut x = Vector6::zeros();
        x.fixed_rows_mut::<3>(0).copy_from(&z);
        let mut p = Matrix6::zeros();
        p.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        let s2 = self.options.initial_speed_sigma_mm_s.powi(2);
        for i in 3..6 {
            p[(i, i)] = s2;
        }
        CvState { x, p, t_s }
    }
}

/// The update with `z`, `R` if its `d²` is within `gate` (module
/// documentation); `None` for an outlier or a singular `S`.
fn update(state: &mut CvState, z: &Vector3<f64>, r: &Matrix3<f64>, gate: f64) -> Option<()> {
    let pp = state.position_covariance();
    let s = pp + r;
    let chol = s.cholesky()?;
    let nu = z - state.position();
    let d2 = nu.dot(&chol.solve(&nu));
    if !(d2.is_finite() && d2 <= gate) {
        return None;
    }
    // K = P Hᵀ S⁻¹: P Hᵀ is P's first three columns (6×3).
    let pht = state.p.fixed_columns::<3>(0).into_owned();
    let k = chol.solve(&pht.transpose()).transpose();
    state.x += k * nu;
    let mut ikh = Matrix6::identity();
    let mut first = ikh.fixed_columns_mut::<3>(0);
    first -= &k;
    state.p = ikh * state.p * ikh.transpose() + k * r * k.transpose();
    state.p = (state.p + state.p.transpose()) * 0.5;
    Some(())
}
