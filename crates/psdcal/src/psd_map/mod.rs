//! The PSD's non-linearity map fitted from a lensless scan (psd_map.json).

pub(crate) mod from_scan;
