//! A calibrated sensor: its model, active area, channel gains and the
//! covariance of its calibration, and what it answers for one measurement —
//! the angle of arrival with its uncertainty (docs/model.md §5, (P39)) and the
//! emitter position on a plane with its 3-D covariance.
//!
//! Amplitude measurements are first turned into impact points with
//! docs/model.md §1 after dividing out the gains (with `∂m/∂g` for the gains'
//! uncertainty). Then, with `J = ∂(a, b)/∂·` from [`crate::aoa`] and
//! `P = P(a, b)` from [`crate::plane`]:
//!
//! ```text
//! Σ_ab = Σ_ab,cal + Σ_ab,meas           (crate::uncertainty)
//! Σ_P  = (∂P/∂(a,b)) Σ_ab (∂P/∂(a,b))ᵀ   3×3, sensor frame, mm²
//! ```

use nalgebra::{DMatrix, Matrix2, Matrix2x3, Matrix3, Vector2};
use psdcal_model::psd::{impact_point_gain_jacobian, impact_point_with_gains, is_on_active_area};
use psdcal_model::{
    Amplitudes, ChannelGains, Model, PsdGeometry, RegionEnd, SensorModel, Stage, ValidRegion,
};

use crate::aoa::{alpha_wrt_ray, angle_of_arrival_with_jacobians, AngleOfArrival, AoaJacobians};
use crate::caution::Caution;
use crate::error::{finite, LocateError};
use crate::plane::{intersect_plane, Plane, PlaneIntersection};
use crate::psd_map::{MapCorrection, SensorPsdMap};
use crate::sensor_chains::{with_aspect_stage, ChainCache, SensorState};
use crate::uncertainty::{point_noise_covariance, propagate, ParameterCovariance};

/// What a sensor measured for one emitter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Measurement {
    /// A measured impact point, mm, sensor frame.
    Point(Vector2<f64>),
    /// The four electrode amplitudes (docs/model.md §1).
    Amplitudes(Amplitudes),
}

/// Options of the location functions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocateOptions {
    /// Standard deviation of the measured point per coordinate, mm (0: the
    /// measurement noise is not counted).
    pub point_sigma_mm: f64,
    /// A ray meeting a plane at less than this angle is flagged
    /// [`Caution::GrazingPlane`], rad.
    pub grazing_warning_rad: f64,
    /// Rays whose largest mutual angle is below this are flagged
    /// [`Caution::NearlyParallelRays`], rad.
    pub ray_angle_warning_rad: f64,
    /// Weight each ray of a triangulation by its inverse covariance (when
    /// every ray has a positive-definite one); `false`: unweighted.
    pub weight_rays: bool,
}

impl Default for LocateOptions {
    /// No point noise; grazing below 10°; rays within 5° of each other;
    /// rays weighted.
    fn default() -> Self {
        Self {
            point_sigma_mm: 0.0,
            grazing_warning_rad: 10f64.to_radians(),
            ray_angle_warning_rad: 5f64.to_radians(),
            weight_rays: true,
        }
    }
}

impl LocateOptions {
    pub(crate) fn check(&self) -> Result<(), LocateError> {
        finite(self.point_sigma_mm, "point sigma")?;
        if self.point_sigma_mm < 0.0 {
            return Err(LocateError::InvalidInput {
                what: "point sigma",
                reason: format!("{} mm; expected zero or more", self.point_sigma_mm),
            });
        }
        finite(self.grazing_warning_rad, "grazing warning angle")?;
        finite(self.ray_angle_warning_rad, "ray angle warning")?;
        Ok(())
    }
}

/// A calibrated sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibratedSensor {
    /// The sensor model.
    pub model: SensorModel,
    /// The PSD's active area.
    pub geometry: PsdGeometry,
    /// Relative channel gains to divide out of amplitudes (`None`: balanced).
    pub gains: Option<ChannelGains>,
    /// Covariance of the calibration's estimated quantities, over names of
    /// [`Self::chain`]'s parameters (an unknown name makes `aoa` fail with
    /// `invalid_covariance`).
    pub covariance: ParameterCovariance,
    /// Where the model's measured → ideal map is one-to-one (docs/model.md
    /// §8.2): computed from `model` and `geometry` by [`Self::new`], or the
    /// region stored with the calibration ([`Self::with_valid_region`]).
    /// Recompute it ([`Self::refresh_valid_region`]) after changing `model`.
    pub valid_region: ValidRegion,
    /// The PSD's non-linearity map, applied to the measured point before
    /// `model` (docs/model.md §8.3); `None` without one.
    pub psd_map: Option<SensorPsdMap>,
    /// The y axis's own scale `a` (`fy = f (1 + a)`, docs/model.md §3.3):
    /// the aspect stage after the PSD's radial one in [`Self::chain`];
    /// `None` without one.
    pub aspect: Option<f64>,
    /// The chains `aoa` evaluates, built once per state of the fields above.
    chains: ChainCache,
}

/// A measured point and, for amplitude input through gains, `∂m/∂g`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasuredPoint {
    /// The impact point, mm.
    pub point: Vector2<f64>,
    /// `∂m/∂(g_x2, g_y1, g_y2)` when the point came from amplitudes.
    pub wrt_gains: Option<Matrix2x3<f64>>,
}

/// An angle of arrival with its uncertainty.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AoaEstimate {
    /// The angle of arrival.
    pub aoa: AngleOfArrival,
    /// Its Jacobians.
    pub jacobians: AoaJacobians,
    /// Covariance of `(a, b)` from the calibration's covariance.
    pub ray_covariance_calibration: Matrix2<f64>,
    /// Covariance of `(a, b)` from the point noise.
    pub ray_covariance_measurement: Matrix2<f64>,
    /// Whether the point is off the active area.
    pub off_active_area: bool,
}

impl AoaEstimate {
    /// Total covariance of `(a, b)`.
    pub fn ray_covariance(&self) -> Matrix2<f64> {
        self.ray_covariance_calibration + self.ray_covariance_measurement
    }

    fn alpha_of_ray_covariance(&self, cov: &Matrix2<f64>) -> Matrix2<f64> {
        let d = alpha_wrt_ray(&self.aoa.ray_ab);
        d * cov * d
    }

    /// Covariance of `(αx, αy)` from the calibration, rad².
    pub fn alpha_covariance_calibration(&self) -> Matrix2<f64> {
        self.alpha_of_ray_covariance(&self.ray_covariance_calibration)
    }

    /// Covariance of `(αx, αy)` from the point noise, rad².
    pub fn alpha_covariance_measurement(&self) -> Matrix2<f64> {
        self.alpha_of_ray_covariance(&self.ray_covariance_measurement)
    }

    /// Total covariance of `(αx, αy)`, rad².
    pub fn alpha_covariance(&self) -> Matrix2<f64> {
        self.alpha_of_ray_covariance(&self.ray_covariance())
    }

    /// The cautions of this estimate.
    pub fn cautions(&self) -> Vec<Caution> {
        if self.off_active_area {
            vec![Caution::OffActiveArea {
                x_mm: self.aoa.measured.x,
                y_mm: self.aoa.measured.y,
            }]
        } else {
            Vec::new()
        }
    }
}

/// A position on a plane with its uncertainty.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneLocation {
    /// The angle of arrival it comes from.
    pub aoa: AoaEstimate,
    /// The intersection.
    pub intersection: PlaneIntersection,
    /// Covariance of the position from the calibration, sensor frame, mm².
    pub covariance_calibration: Matrix3<f64>,
    /// Covariance of the position from the point noise, mm².
    pub covariance_measurement: Matrix3<f64>,
    /// Reasons for care (off the active area, grazing plane).
    pub cautions: Vec<Caution>,
}

impl PlaneLocation {
    /// Total covariance of the position, mm².
    pub fn covariance(&self) -> Matrix3<f64> {
        self.covariance_calibration + self.covariance_measurement
    }
}

impl CalibratedSensor {
    /// A sensor with balanced channels and no calibration uncertainty.
    pub fn new(model: SensorModel, geometry: PsdGeometry) -> Self {
        Self {
            valid_region: ValidRegion::of_sensor_model(&model, &geometry),
            model,
            geometry,
            gains: None,
            covariance: ParameterCovariance::none(),
            psd_map: None,
            aspect: None,
            chains: ChainCache::default(),
        }
    }

    /// The same sensor with the aspect stage (`fy = f (1 + a)`); the valid
    /// region is recomputed for the whole chain.
    pub fn with_aspect(mut self, a: f64) -> Self {
        self.aspect = Some(a);
        self.valid_region = ValidRegion::of_model(&self.chain(), &self.geometry);
        self
    }

    /// The standard chain with the aspect stage when the sensor has one
    /// (no gains, no PSD map): the map of a corrected measured point.
    pub fn lens_chain(&self) -> Model {
        let chain = Model::standard(&self.model);
        match self.aspect {
            None => chain,
            Some(a) => with_aspect_stage(&chain, a),
        }
    }

    /// The same sensor with a PSD map first in its chain; the valid region
    /// is recomputed for the whole chain (it ends at the map's hull).
    pub fn with_psd_map(mut self, map: SensorPsdMap) -> Self {
        self.psd_map = Some(map);
        self.valid_region = ValidRegion::of_model(&self.chain(), &self.geometry);
        self
    }

    /// The measured point corrected by the PSD map (the identity without
    /// one), with `∂m'/∂m`; outside the map's hull, `BeyondValidRegion`.
    pub fn map_corrected(&self, point: &Vector2<f64>) -> Result<MapCorrection, LocateError> {
        match &self.psd_map {
            None => Ok(MapCorrection {
                point: *point,
                wrt_measured: Matrix2::identity(),
                wrt_block: Vec::new(),
            }),
            Some(map) if !map.contains(point) => {
                let d = point - self.valid_region.centre();
                let distance_mm = d.norm();
                let limit_mm = match map.stage.hull() {
                    Some(h) if distance_mm > 0.0 => {
                        h.exit_distance(&self.valid_region.centre(), &(d / distance_mm))
                    }
                    _ => distance_mm,
                };
                Err(LocateError::BeyondValidRegion {
                    x: point.x,
                    y: point.y,
                    distance_mm,
                    limit_mm,
                    end: RegionEnd::DomainEdge,
                })
            }
            Some(map) => Ok(map.correct(point)),
        }
    }

    /// The same sensor with a given valid region (the one stored with its
    /// calibration), within the sensor's domain (its PSD map's scan hull).
    pub fn with_valid_region(mut self, region: ValidRegion) -> Self {
        let domain = self
            .psd_map
            .as_ref()
            .and_then(|_| self.chain().measured_domain().cloned());
        self.valid_region = region.with_domain(domain);
        self
    }

    /// Recomputes the valid region from `model` and `geometry`.
    pub fn refresh_valid_region(&mut self) {
        self.valid_region = match (&self.psd_map, self.aspect) {
            (None, None) => ValidRegion::of_sensor_model(&self.model, &self.geometry),
            _ => ValidRegion::of_model(&self.chain(), &self.geometry),
        };
    }

    /// `Ok` when `point` is inside the valid region, else
    /// [`LocateError::BeyondValidRegion`] (a non-finite point is
    /// [`LocateError::NonFinite`]).
    pub fn check_valid_region(&self, point: &Vector2<f64>) -> Result<(), LocateError> {
        check_region(&self.valid_region, point)
    }

    /// The same sensor with a covariance.
    pub fn with_covariance(mut self, covariance: ParameterCovariance) -> Self {
        self.covariance = covariance;
        self
    }

    /// The same sensor with channel gains.
    pub fn with_gains(mut self, gains: ChannelGains) -> Self {
        self.gains = Some(gains);
        self
    }

    /// The sensor's model as a chain of stages (psdcal-model's `Model`: the
    /// standard chain and its gains stage, unit gains when the sensor has
    /// none): the flat parameter names its covariance is resolved against.
    pub fn chain(&self) -> Model {
        let chain = Model::standard_with_gains(
            &self.model,
            self.geometry,
            &self.gains.unwrap_or(ChannelGains::UNIT),
        );
        let chain = match self.aspect {
            None => chain,
            Some(a) => with_aspect_stage(&chain, a),
        };
        let Some(map) = &self.psd_map else {
            return chain;
        };
        let Ok(mut with_map) = chain.with_stage(0, Box::new(map.stage.clone())) else {
            return chain;
        };
        for (p, v) in map.stage.parameters().iter().zip(&map.block) {
            let _ = with_map.set(&p.name, *v);
        }
        with_map
    }

    /// The measured impact point of a measurement.
    pub fn measured_point(&self, measurement: &Measurement) -> Result<MeasuredPoint, LocateError> {
        match measurement {
            Measurement::Point(p) => Ok(MeasuredPoint {
                point: *p,
                wrt_gains: None,
            }),
            Measurement::Amplitudes(a) => match &self.gains {
                Some(g) => {
                    let (point, jac) = impact_point_gain_jacobian(&self.geometry, a, g)?;
                    Ok(MeasuredPoint {
                        point,
                        wrt_gains: Some(jac),
                    })
                }
                None => Ok(MeasuredPoint {
                    point: impact_point_with_gains(&self.geometry, a, &ChannelGains::UNIT)?,
                    wrt_gains: None,
                }),
            },
        }
    }

    /// The angle of arrival of a measurement with its uncertainty.
    ///
    /// ```
    /// use nalgebra::{DMatrix, Vector2};
    /// use psdcal_locate::{CalibratedSensor, LocateOptions, Measurement, ParameterCovariance};
    /// use psdcal_model::{Param, PsdGeometry, SensorModel};
    ///
    /// // Only cx uncertain (σ = 0.01 mm): σ_αx = σ_cx · cos²αx / f at the centre.
    /// let cov = ParameterCovariance::from_params(&[Param::Cx], &DMatrix::from_element(1, 1, 1e-4)).unwrap();
    /// let sensor = CalibratedSensor::new(SensorModel::pinhole(8.0, 0.0, 0.0), PsdGeometry::default())
    ///     .with_covariance(cov);
    /// let est = sensor.aoa(&Measurement::Point(Vector2::zeros()), &LocateOptions::default()).unwrap();
    /// let sigma_x = est.alpha_covariance()[(0, 0)].sqrt();
    /// assert!((sigma_x - 0.01 / 8.0).abs() < 1e-15);
    /// ```
    pub fn aoa(
        &self,
        measurement: &Measurement,
        options: &LocateOptions,
    ) -> Result<AoaEstimate, LocateError> {
        options.check()?;
        let measured = self.measured_point(measurement)?;
        self.check_valid_region(&measured.point)?;
        let corrected = self.map_corrected(&measured.point)?;
        let state = SensorState {
            model: &self.model,
            geometry: &self.geometry,
            gains: &self.gains,
            psd_map: &self.psd_map,
            covariance: &self.covariance,
            aspect: &self.aspect,
        };
        let chains = self.chains.get(state, || self.chain());
        let (mut aoa, mut jacobians) =
            angle_of_arrival_with_jacobians(&chains.standard, &corrected.point)?;
        // ∂(a, b)/∂m' before the map's chain rule, for the map's columns.
        let ray_wrt_corrected = jacobians.ray_wrt_measured;
        aoa.measured = measured.point;
        jacobians.ray_wrt_measured = ray_wrt_corrected * corrected.wrt_measured;
        let wrt_gains = measured.wrt_gains.map(|g| jacobians.ray_wrt_measured * g);
        let ray_covariance_calibration = if self.covariance.is_empty() {
            Matrix2::zeros()
        } else {
            // ∂(a, b)/∂θ over the chain's flat parameters: the model's
            // columns, and the gains' for amplitudes through gains.
            let chain = &chains.chain;
            let mut wrt_params = DMatrix::zeros(2, chain.len());
            for (k, column) in chains.model_columns.iter().enumerate() {
                if let Some(c) = *column {
                    wrt_params.set_column(c, &jacobians.ray_wrt_model.column(k));
                }
            }
            if let Some((k, c)) = chains.aspect_columns {
                let standard = &chains.standard;
                let mut jac = standard.jacobian_buffer();
                standard.ray_with_jacobians(&corrected.point, &mut jac);
                wrt_params.set_column(c, &jac.column(k));
            }
            if let (Some(g), Some(columns)) = (wrt_gains, chains.gain_columns) {
                for (k, c) in columns.into_iter().enumerate() {
                    wrt_params.set_column(c, &g.column(k));
                }
            }
            for (k, column) in chains.map_columns.iter().enumerate() {
                if let Some(c) = *column {
                    let column =
                        Vector2::new(corrected.wrt_block[2 * k], corrected.wrt_block[2 * k + 1]);
                    wrt_params.set_column(c, &(ray_wrt_corrected * column));
                }
            }
            match &chains.covariance_columns {
                Some(columns) => {
                    let out = self.covariance.propagate_columns(&wrt_params, columns);
                    Matrix2::new(out[(0, 0)], out[(0, 1)], out[(1, 0)], out[(1, 1)])
                }
                None => propagate(&self.covariance, chain, &wrt_params)?,
            }
        };
        let ray_covariance_measurement =
            point_noise_covariance(&jacobians.ray_wrt_measured, options.point_sigma_mm);
        Ok(AoaEstimate {
            aoa,
            jacobians,
            ray_covariance_calibration,
            ray_covariance_measurement,
            off_active_area: !is_on_active_area(&self.geometry, &measured.point),
        })
    }

    /// The position of the emitter on `plane` (sensor frame) with its
    /// covariance.
    ///
    /// ```
    /// use nalgebra::Vector2;
    /// use psdcal_locate::{CalibratedSensor, LocateOptions, Measurement, Plane};
    /// use psdcal_model::{PsdGeometry, SensorModel};
    ///
    /// let sensor = CalibratedSensor::new(SensorModel::paper_lens1(), PsdGeometry::default());
    /// let at = sensor
    ///     .locate_on_plane(
    ///         &Measurement::Point(Vector2::new(1.0, 2.0)),
    ///         &Plane::parallel(5000.0).unwrap(),
    ///         &LocateOptions { point_sigma_mm: 1e-3, ..LocateOptions::default() },
    ///     )
    ///     .unwrap();
    /// assert_eq!(at.intersection.position.z, 5000.0);
    /// // 1 µm on the PSD is about S/f = 200 µm at 5 m.
    /// let sigma_x = at.covariance()[(0, 0)].sqrt();
    /// assert!((sigma_x / 0.2 - 1.0).abs() < 0.05);
    /// ```
    pub fn locate_on_plane(
        &self,
        measurement: &Measurement,
        plane: &Plane,
        options: &LocateOptions,
    ) -> Result<PlaneLocation, LocateError> {
        let aoa = self.aoa(measurement, options)?;
        let intersection = intersect_plane(plane, &aoa.aoa.ray_ab)?;
        let j = &intersection.wrt_ray;
        let covariance_calibration = j * aoa.ray_covariance_calibration * j.transpose();
        let covariance_measurement = j * aoa.ray_covariance_measurement * j.transpose();
        let mut cautions = aoa.cautions();
        if intersection.grazing_angle < options.grazing_warning_rad {
            cautions.push(Caution::GrazingPlane {
                angle_deg: intersection.grazing_angle.to_degrees(),
            });
        }
        Ok(PlaneLocation {
            aoa,
            intersection,
            covariance_calibration: (covariance_calibration + covariance_calibration.transpose())
                * 0.5,
            covariance_measurement: (covariance_measurement + covariance_measurement.transpose())
                * 0.5,
            cautions,
        })
    }
}

/// `Ok` when `point` is inside `region`: [`LocateError::NonFinite`] for a
/// non-finite point, [`LocateError::BeyondValidRegion`] outside.
pub(crate) fn check_region(region: &ValidRegion, point: &Vector2<f64>) -> Result<(), LocateError> {
    finite(point.x, "measured x")?;
    finite(point.y, "measured y")?;
    region
        .check(point)
        .map_err(|o| LocateError::BeyondValidRegion {
            x: point.x,
            y: point.y,
            distance_mm: o.distance_mm,
            limit_mm: o.limit_mm,
            end: o.end,
        })
}
