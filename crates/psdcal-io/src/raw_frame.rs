//! One sample of a raw recording and what every raw format shares: the
//! channels' names and the tolerance on the sample rate.

/// One sample of the four channels, volts: `[vx1, vx2, vy1, vy2]`.
pub type Frame = [f64; 4];

/// Relative tolerance on the time steps of a `t_s` column (and on the
/// agreement of `t_s` with `--rate`).
pub const RATE_TOLERANCE: f64 = 1e-3;

/// The four channels, in frame order.
pub(crate) const CHANNELS: [&str; 4] = ["vx1", "vx2", "vy1", "vy2"];
