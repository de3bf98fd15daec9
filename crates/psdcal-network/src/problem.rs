//! The bundle adjustment of a network as a problem for the one solver
//! (docs/network.md).
//!
//! Unknowns: each sensor's `sensor_from_world` `T_s` (6; held at the
//! identity for sensor 0 when no static frame fixes the world) and its freed
//! lens parameters `θ_s` — together the global block — and one wand pose
//! `W_f = world_from_wand` per frame (the eliminated blocks of six).
//!
//! Residuals (each whitened so that the cost is a χ²):
//!
//! ```text
//! r_k  = M_k (n(T_s P) − ray(θ_s; m_k)) / σ      a sighting of the LED at P
//! r_s  = L_s⁻¹ (θ_s − θ_s,lab),  Σ_s,lab = L_s L_sᵀ      the lab prior
//! ```
//!
//! with `P = W_f L_l` for wand LED `l` in frame `f` (or the static LED's
//! world position), `n(X, Y, Z) = (X/Z, Y/Z)`, `ray(θ; m)` the sensor's chain
//! measured → ray, and `M_k = (∂ray/∂m)⁻¹` at the sighting, frozen for one
//! solve: to first order `r_k σ` is the image-plane error `project − m`
//! (mm on the PSD) without inverting the distortion (Newton) at every
//! evaluation. `σ` is the point noise (estimated, [`crate::adjust`]). `∂r/∂W_f =
//! ∂m/∂P · ∂P/∂(rvec_f, t_f)`, `P = R_f L_l + t_f`. A collinear wand's roll
//! does not move its LEDs; the term `ε (rvec_f − rvec_f,start)` (`ε = 1e-6`
//! per radian, far below any real information) keeps its block regular
//! without moving what the data determine. Each sighting's Jacobian holds
//! only its sensor's columns (the solver's sparse terms).

use nalgebra::{DMatrix, Matrix2, Matrix2x3, Vector2, Vector3};
use psdcal_model::{ChainJacobian, Model, ModelError, Pose};
use psdcal_solver::normal_equations::{ResidualTerm, Step};
use psdcal_solver::solver::Problem;

use crate::data::{Led, NetworkData};
use crate::NetworkError;

/// Least depth of a point in front of a sensor, mm.
pub const MIN_DEPTH_MM: f64 = 1e-9;

/// Weight of a collinear wand's roll anchor, per radian (whitened units).
pub const ROLL_ANCHOR: f64 = 1e-6;

/// Every sensor's pose and model, every placed frame's wand pose.
#[derive(Debug, Clone)]
pub struct NetworkState {
    /// `sensor_from_world` per sensor.
    pub sensors: Vec<Pose>,
    /// The model per sensor.
    pub models: Vec<Model>,
    /// `world_from_wand` per block.
    pub wands: Vec<Pose>,
}

/// Where each sensor's unknowns sit in the global block.
#[derive(Debug, Clone)]
pub struct Layout {
    /// First column of the sensor's pose, when free.
    pub pose: Vec<Option<usize>>,
    /// Columns of the sensor's freed lens parameters.
    pub lens: Vec<Vec<usize>>,
    /// Their indices in the sensor's model.
    pub lens_params: Vec<Vec<usize>>,
    /// Every global column of each sensor (pose then lens).
    pub columns: Vec<Vec<usize>>,
    /// Global size.
    pub len: usize,
}

impl Layout {
    /// The layout for `data`; sensor 0's pose is held when `hold_first`.
    pub fn new(data: &NetworkData, hold_first: bool) -> Self {
        let mut next = 0;
        let (mut pose, mut lens, mut lens_params, mut columns) = (vec![], vec![], vec![], vec![]);
        for (s, sensor) in data.sensors.iter().enumerate() {
            let mut cols = Vec::new();
            if s == 0 && hold_first {
                pose.push(None);
            } else {
                pose.push(Some(next));
                cols.extend(next..next + 6);
                next += 6;
            }
            let n = sensor.prior_names.len();
            lens.push((next..next + n).collect::<Vec<_>>());
            cols.extend(next..next + n);
            next += n;
            lens_params.push(
                sensor
                    .prior_names
                    .iter()
                    .map(|name| sensor.model.index(name).unwrap_or(0))
                    .collect(),
            );
            columns.push(cols);
        }
        Self {
            pose,
            lens,
            lens_params,
            columns,
            len: next,
        }
    }
}

/// The bundle adjustment (module documentation).
#[derive(Debug, Clone)]
pub struct NetworkProblem<'a> {
    data: &'a NetworkData,
    layout: &'a Layout,
    /// Observation indices per block.
    by_block: Vec<Vec<usize>>,
    /// Static-frame observations used.
    statics: Vec<usize>,
    /// Whitening of the point residuals, 1/σ (mm⁻¹).
    inv_sigma: f64,
    /// Per sensor: `L⁻¹` of the lab covariance and the lab values.
    priors: Vec<(DMatrix<f64>, Vec<f64>)>,
    /// Anchors of collinear wands' rolls (start rotations), when collinear.
    anchors: Option<Vec<Vector3<f64>>>,
    /// Per observation, `M_k` (module documentation).
    to_image: Vec<Matrix2<f64>>,
}

impl<'a> NetworkProblem<'a> {
    /// The problem over the observations `by_block` (per block) and
    /// `statics`, with point noise `sigma_mm`.
    pub fn new(
        data: &'a NetworkData,
        layout: &'a Layout,
        by_block: Vec<Vec<usize>>,
        statics: Vec<usize>,
        sigma_mm: f64,
        start_wands: &[Pose],
        models: &[Model],
    ) -> Result<Self, NetworkError> {
        let to_image = data
            .observations
            .iter()
            .map(|o| {
                let model = &models[o.sensor];
                let mut jac = model.jacobian_buffer();
                jac.restrict_to(&[]);
                model.ray_with_jacobians(&o.measured, &mut jac);
                jac.wrt_point.try_inverse().unwrap_or_else(Matrix2::zeros)
            })
            .collect();
        let priors = data
            .sensors
            .iter()
            .map(|s| {
                let chol = s.prior_covariance.clone().cholesky().ok_or_else(|| {
                    NetworkError::Input(format!(
                        "sensor '{}': its lab covariance is not positive definite",
                        s.id
                    ))
                })?;
                let l_inv = chol.l().try_inverse().ok_or_else(|| {
                    NetworkError::Input(format!("sensor '{}': singular lab covariance", s.id))
                })?;
                let mean = s
                    .prior_names
                    .iter()
                    .map(|n| s.model.get(n).unwrap_or(0.0))
                    .collect();
                Ok((l_inv, mean))
            })
            .collect::<Result<Vec<_>, NetworkError>>()?;
        let anchors = data
            .wand_is_collinear()
            .then(|| start_wands.iter().map(|w| w.rvec).collect());
        Ok(Self {
            data,
            layout,
            by_block,
            statics,
            inv_sigma: 1.0 / sigma_mm,
            priors,
            anchors,
            to_image,
        })
    }

    /// The observations of each block.
    pub fn blocks(&self) -> &[Vec<usize>] {
        &self.by_block
    }

    /// The static-frame observations used.
    pub fn statics(&self) -> &[usize] {
        &self.statics
    }

    /// The world point of observation `k` in `state` (block `b`).
    pub fn point(&self, state: &NetworkState, b: Option<usize>, k: usize) -> Vector3<f64> {
        match self.data.observations[k].led {
            Led::Wand(l) => state.wands[b.unwrap_or(0)].transform(&self.data.wand[l]),
            Led::Frame(l) => self.data.frame_leds[l],
        }
    }

    /// The unwhitened residual (mm) of observation `k` (block `b`).
    pub fn residual_mm(
        &self,
        state: &NetworkState,
        b: Option<usize>,
        k: usize,
    ) -> Result<Vector2<f64>, ModelError> {
        let o = &self.data.observations[k];
        let p = state.sensors[o.sensor].transform(&self.point(state, b, k));
        if p.z.is_nan() || p.z <= MIN_DEPTH_MM {
            return Err(ModelError::BehindSensor { zc: p.z });
        }
        let n = Vector2::new(p.x / p.z, p.y / p.z);
        Ok(self.to_image[k] * (n - state.models[o.sensor].ray(&o.measured)))
    }

    fn error(&self, k: usize, e: ModelError) -> NetworkError {
        let o = &self.data.observations[k];
        NetworkError::Numerical {
            stage: "bundle adjustment",
            reason: format!(
                "sensor '{}', frame '{}': {e}",
                self.data.sensors[o.sensor].id,
                self.data.frames.get(o.frame).map_or("-", String::as_str)
            ),
        }
    }

    /// Visits one sighting's term (module documentation).
    /// `at`: the block and observation; `scratch`: each sensor's rotation
    /// Jacobian and chain buffer.
    fn sighting(
        &self,
        state: &NetworkState,
        at: (
            Option<usize>,
            usize,
            Option<&psdcal_model::RotationJacobian>,
        ),
        scratch: (&[psdcal_model::RotationJacobian], &mut [ChainJacobian]),
        visit: &mut dyn FnMut(&ResidualTerm<'_>, Option<&[usize]>),
    ) -> Result<(), NetworkError> {
        let (b, k, wand_rotation) = at;
        let (rotations, jacs) = scratch;
        let o = &self.data.observations[k];
        let s = o.sensor;
        let (p, dp_dwand) = match (o.led, b, wand_rotation) {
            (Led::Wand(l), Some(b), Some(rot)) => {
                let (p, j, _) =
                    state.wands[b].transform_with_jacobians_using(rot, &self.data.wand[l]);
                (p, Some(j))
            }
            _ => (self.point(state, b, k), None),
        };
        let (pc, dpc_dpose, rot) =
            state.sensors[s].transform_with_jacobians_using(&rotations[s], &p);
        if pc.z.is_nan() || pc.z <= MIN_DEPTH_MM {
            return Err(self.error(k, ModelError::BehindSensor { zc: pc.z }));
        }
        let iz = 1.0 / pc.z;
        let n = Vector2::new(pc.x * iz, pc.y * iz);
        let dn = Matrix2x3::new(iz, 0.0, -n.x * iz, 0.0, iz, -n.y * iz);
        let jac = &mut jacs[s];
        let ray = state.models[s].ray_with_jacobians(&o.measured, jac);
        let m = self.to_image[k] * self.inv_sigma;
        let r = m * (n - ray);
        let md = m * dn;
        let d_pose = md * dpc_dpose;
        let cols = &self.layout.columns[s];
        let mut a = [0.0; 2 * 32];
        let mut j = 0;
        if self.layout.pose[s].is_some() {
            for c in 0..6 {
                a[2 * j] = d_pose[(0, c)];
                a[2 * j + 1] = d_pose[(1, c)];
                j += 1;
            }
        }
        for &c in &self.layout.lens_params[s] {
            let v = -(m * Vector2::new(jac.wrt_params[2 * c], jac.wrt_params[2 * c + 1]));
            a[2 * j] = v.x;
            a[2 * j + 1] = v.y;
            j += 1;
        }
        let block_j = dp_dwand.map(|d| md * rot * d);
        visit(
            &ResidualTerm {
                r: r.as_slice(),
                a: &a[..2 * j],
                block: match (b, &block_j) {
                    (Some(b), Some(bj)) => Some((b, bj.as_slice())),
                    _ => None,
                },
            },
            Some(cols),
        );
        Ok(())
    }
}

impl Problem for NetworkProblem<'_> {
    type State = NetworkState;
    type Error = NetworkError;

    fn global_len(&self) -> usize {
        self.layout.len
    }

    fn block_count(&self) -> usize {
        self.by_block.len()
    }

    fn evaluate(
        &self,
        state: &NetworkState,
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>),
    ) -> Result<(), NetworkError> {
        let p = self.layout.len;
        let mut dense = vec![0.0; 0];
        self.evaluate_sparse(state, jacobians, &mut |term, columns| {
            if !jacobians {
                return visit(term);
            }
            let d = term.r.len();
            dense.clear();
            dense.resize(d * p, 0.0);
            if let Some(cols) = columns {
                for (j, &c) in cols.iter().enumerate() {
                    dense[d * c..d * c + d].copy_from_slice(&term.a[d * j..d * j + d]);
                }
            }
            visit(&ResidualTerm {
                r: term.r,
                a: &dense,
                block: term.block,
            });
        })
    }

    fn evaluate_sparse(
        &self,
        state: &NetworkState,
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>, Option<&[usize]>),
    ) -> Result<(), NetworkError> {
        if !jacobians {
            let sightings = self
                .by_block
                .iter()
                .enumerate()
                .flat_map(|(b, obs)| obs.iter().map(move |&k| (Some(b), k)));
            let statics = self.statics.iter().map(|&k| (None, k));
            for (b, k) in sightings.chain(statics) {
                let r = self
                    .residual_mm(state, b, k)
                    .map_err(|e| self.error(k, e))?
                    * self.inv_sigma;
                visit(
                    &ResidualTerm {
                        r: r.as_slice(),
                        a: &[],
                        block: None,
                    },
                    None,
                );
            }
            self.visit_priors(state, false, visit);
            self.visit_anchors(state, false, visit);
            return Ok(());
        }
        let rotations: Vec<_> = state.sensors.iter().map(Pose::rotation_jacobian).collect();
        let mut jacs: Vec<ChainJacobian> = state
            .models
            .iter()
            .zip(&self.layout.lens_params)
            .map(|(m, cols)| {
                let mut j = m.jacobian_buffer();
                j.restrict_to(cols);
                j
            })
            .collect();
        for (b, obs) in self.by_block.iter().enumerate() {
            let rot = state.wands[b].rotation_jacobian();
            for &k in obs {
                self.sighting(
                    state,
                    (Some(b), k, Some(&rot)),
                    (&rotations, &mut jacs),
                    visit,
                )?;
            }
        }
        for &k in &self.statics {
            self.sighting(state, (None, k, None), (&rotations, &mut jacs), visit)?;
        }
        self.visit_priors(state, true, visit);
        self.visit_anchors(state, true, visit);
        Ok(())
    }

    fn apply_step(&self, state: &NetworkState, step: &Step) -> Option<NetworkState> {
        let mut next = state.clone();
        for s in 0..next.sensors.len() {
            if let Some(c) = self.layout.pose[s] {
                next.sensors[s] = state.sensors[s].stepped(&step.da.as_slice()[c..c + 6]);
            }
            let cols = &self.layout.lens[s];
            if !cols.is_empty() {
                let delta: Vec<f64> = cols.iter().map(|&c| step.da[c]).collect();
                next.models[s] = state.models[s].stepped(&self.layout.lens_params[s], &delta);
            }
        }
        for (w, db) in next.wands.iter_mut().zip(&step.db) {
            *w = w.stepped(db.as_slice());
        }
        next.sensors
            .iter()
            .chain(&next.wands)
            .all(|p| p.rvec.iter().chain(p.t.iter()).all(|v| v.is_finite()))
            .then_some(next)
    }
}

impl NetworkProblem<'_> {
    fn visit_priors(
        &self,
        state: &NetworkState,
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>, Option<&[usize]>),
    ) {
        for (s, (l_inv, mean)) in self.priors.iter().enumerate() {
            let n = mean.len();
            if n == 0 {
                continue;
            }
            let values = state.models[s].values();
            let dev: Vec<f64> = self.layout.lens_params[s]
                .iter()
                .zip(mean)
                .map(|(&c, m)| values[c] - m)
                .collect();
            let r: Vec<f64> = (0..n)
                .map(|i| (0..n).map(|j| l_inv[(i, j)] * dev[j]).sum())
                .collect();
            if jacobians {
                let a: Vec<f64> = (0..n)
                    .flat_map(|j| (0..n).map(move |i| (i, j)))
                    .map(|(i, j)| l_inv[(i, j)])
                    .collect();
                visit(
                    &ResidualTerm {
                        r: &r,
                        a: &a,
                        block: None,
                    },
                    Some(&self.layout.lens[s]),
                );
            } else {
                visit(
                    &ResidualTerm {
                        r: &r,
                        a: &[],
                        block: None,
                    },
                    None,
                );
            }
        }
    }

    fn visit_anchors(
        &self,
        state: &NetworkState,
        jacobians: bool,
        visit: &mut dyn FnMut(&ResidualTerm<'_>, Option<&[usize]>),
    ) {
        let Some(anchors) = &self.anchors else {
            return;
        };
        let mut b6 = [0.0; 18];
        for k in 0..3 {
            b6[3 * k + k] = ROLL_ANCHOR;
        }
        for (b, (w, a0)) in state.wands.iter().zip(anchors).enumerate() {
            let r = (w.rvec - a0) * ROLL_ANCHOR;
            visit(
                &ResidualTerm {
                    r: r.as_slice(),
                    a: &[],
                    block: jacobians.then_some((b, &b6[..])),
                },
                jacobians.then_some(&[][..]),
            );
        }
    }
}
