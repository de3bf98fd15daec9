//! The paper's simulated set-up (`docs/model.md` §7): what the paper leaves
//! open and psdcal fixes once, for the simulator, the example data and the
//! tests alike.
//!
//! The paper's lenses are [`SensorModel::paper_lens1`] and
//! [`SensorModel::paper_lens2`], its PSD distortion
//! [`SensorModel::PAPER_L1`]. The paper gives no template coordinates: psdcal's
//! `scatter14` template is [`SCATTER14_MM`], 14 LEDs within ±150 mm with no
//! three collinear (the paper's "unaligned" template).
//!
//! [`SensorModel::paper_lens1`]: crate::SensorModel::paper_lens1
//! [`SensorModel::paper_lens2`]: crate::SensorModel::paper_lens2
//! [`SensorModel::PAPER_L1`]: crate::SensorModel::PAPER_L1

use nalgebra::Vector2;

/// The 14 unaligned LEDs of the `scatter14` template, `(X, Y)` in mm on the
/// template plane. The only definition in the repository: everything else
/// (simulator, example data, test support) takes them from here.
pub const SCATTER14_MM: [(f64, f64); 14] = [
    (-140.0, -120.0),
    (-60.0, -135.0),
    (35.0, -110.0),
    (120.0, -140.0),
    (-120.0, -40.0),
    (-25.0, -55.0),
    (70.0, -30.0),
    (145.0, -60.0),
    (-135.0, 50.0),
    (-50.0, 35.0),
    (40.0, 60.0),
    (130.0, 25.0),
    (-80.0, 130.0),
    (90.0, 140.0),
];

/// [`SCATTER14_MM`] as points, in LED order.
pub fn scatter14() -> Vec<Vector2<f64>> {
    SCATTER14_MM
        .iter()
        .map(|&(x, y)| Vector2::new(x, y))
        .collect()
}
