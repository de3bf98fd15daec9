//! A simulated room calibrated from no guess: poses, lenses, honesty.

mod common;

use psdcal_network::{calibrate_network, NetworkOptions};
use psdcal_sim::network_room::NetworkRoomOptions;

#[test]
fn a_short_wave_places_every_sensor() {
    let options = NetworkRoomOptions {
        duration_s: 20.0,
        ..NetworkRoomOptions::default()
    };
    let room = common::room(&options, 7);
    let data = common::data(&room, true);
    let t = std::time::Instant::now();
    let result = calibrate_network(&data, &NetworkOptions::default()).unwrap();
    eprintln!("calibrated in {:?}, {} iterations", t.elapsed(), result.iterations);
    eprintln!("sigma {} (sim {})", result.sigma_mm, room.point_sigma_mm);
    eprintln!("dropped {} (bad {})", result.dropped.len(), room.bad_frames.len());
    let mut z2 = Vec::new();
    for (k, e) in result.sensors.iter().enumerate() {
        let truth = common::true_sensor_from_world(&room, k, true);
        let dp = common::centre(&truth) - e.position_mm;
        let dr = common::rotation_error_deg(&truth, &e.sensor_from_world);
        let sd = e.position_covariance.diagonal().map(f64::sqrt);
        eprintln!("{k}: err {:?} mm, σ {:?}, rot {dr:.4}°, pts {}", dp.as_slice(), sd.as_slice(), e.points);
        for i in 0..3 {
            z2.push((dp[i] / sd[i]).powi(2));
        }
    }
    let z = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    eprintln!("RMS z {z}");
    eprintln!("{:?}", result.diagnostics.items);
}
