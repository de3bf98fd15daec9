//! Raw recordings to amplitudes: demodulation of records and tracking of a live sample stream.

pub(crate) mod demodulate;
pub(crate) mod track;
pub(crate) mod track_rig;
