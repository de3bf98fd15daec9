//! Using a calibration: the sensor from calibration.json, ideal points, angles of arrival, positions, error maps, comparisons, exports and evaluations.

pub(crate) mod aoa;
pub(crate) mod correct;
pub(crate) mod diff;
pub(crate) mod evaluate;
pub(crate) mod export;
pub(crate) mod focal_check;
pub(crate) mod loaded_sensor;
pub(crate) mod locate;
pub(crate) mod map;
pub(crate) mod point_rows;
