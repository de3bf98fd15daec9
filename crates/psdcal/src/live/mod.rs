//! Live positions: the rig's positions served over HTTP with a 3-D page.

pub(crate) mod rig_json;
pub(crate) mod serve;
