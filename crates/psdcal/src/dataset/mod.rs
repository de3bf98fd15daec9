//! Reading and validating a calibration data set, from files or memory.

pub(crate) mod data_set;
