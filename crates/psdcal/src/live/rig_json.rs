//! The rig as `serve` shows it (`GET /rig`): per sensor its `id`, its
//! position `t_mm` and `rvec` (world frame), its optical axis `axis` (the
//! sensor's `z` in the world frame, a unit vector) and its half field of
//! view `half_fov_rad` along x and y: `atan(L / 2 / f)`, `L` the active
//! area's side and `f` the calibrated focal length.

use psdcal_locate::Rig;
use serde_json::{json, Value};

/// The rig's JSON (module documentation).
pub(crate) fn rig_json(rig: &Rig) -> Value {
    let sensors: Vec<Value> = rig
        .sensors()
        .iter()
        .map(|s| {
            let pose = &s.world_from_sensor;
            let r = pose.rotation();
            let f = s.sensor.model.intrinsics.f.abs().max(1e-9);
            let g = &s.sensor.geometry;
            json!({
                "id": s.id,
                "t_mm": pose.t.as_slice(),
                "rvec": pose.rvec.as_slice(),
                "axis": [r[(0, 2)], r[(1, 2)], r[(2, 2)]],
                "x_axis": [r[(0, 0)], r[(1, 0)], r[(2, 0)]],
                "y_axis": [r[(0, 1)], r[(1, 1)], r[(2, 1)]],
                "half_fov_rad": [(g.lx / 2.0 / f).atan(), (g.ly / 2.0 / f).atan()],
            })
        })
        .collect();
    json!({ "sensors": sensors })
}
