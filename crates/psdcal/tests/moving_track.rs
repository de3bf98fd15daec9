//! `track --rig --filter cv` on a simulated recording of moving LEDs
//! (`simulate_moving`: four sensors at the ceiling corners, 20 kHz, two LEDs
//! by frequency 2–5 m away, up to 1 m/s, one pausing, every impairment):
//! against the true paths (psdcal-sim's scene, evaluated at each window's
//! centre), the filtered positions beat the per-window intersections
//! (RMS ≤ 0.8×) after 0.5 s, their NEES is consistent (mean 1.5–6) and
//! ≥ 90 % of them lie inside their 99 % ellipsoid; the rows keep the
//! unfiltered `t_s`.

use std::path::Path;

use nalgebra::{Matrix3, Vector3};
use psdcal::{
    simulate_moving, DemodConfig, Lens, MovingRequest, TrackFilter, TrackRequest, TrackTarget,
    DEFAULT_MOVING_NOISE_V,
};
use psdcal_sim::moving::MovingScene;

const WINDOW_S: f64 = 0.05;

fn track(dir: &Path, filter: TrackFilter) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    psdcal::track(
        &TrackRequest {
            target: TrackTarget::Rig(dir.join("rig.json")),
            rate_hz: None,
            tones: dir.join("tones.csv"),
            window_s: WINDOW_S,
            config: DemodConfig::default(),
            raw: Some(dir.join("raw.tdms")),
            channels: Vec::new(),
            limits: Default::default(),
            filter,
        },
        "".as_bytes(),
        &mut out,
    )
    .unwrap();
    String::from_utf8(out)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect()
}

fn position(row: &[String]) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let v = |i: usize| row[i].parse::<f64>().ok();
    let p = Vector3::new(v(3)?, v(4)?, v(5)?);
    let (sx, sy, sz) = (v(6)?, v(7)?, v(8)?);
    let (cxy, cxz, cyz) = (v(9)?, v(10)?, v(11)?);
    Some((
        p,
        Matrix3::new(sx * sx, cxy, cxz, cxy, sy * sy, cyz, cxz, cyz, sz * sz),
    ))
}

/// Per row after the settling: the error and its NEES.
fn errors(rows: &[Vec<String>]) -> Vec<(f64, f64)> {
    let scene = MovingScene::ceiling_corners();
    rows.iter()
        .filter_map(|row| {
            let t: f64 = row[0].parse().unwrap();
            if t < 0.5 {
                return None;
            }
            let led = scene.leds.iter().find(|l| l.name == row[1]).unwrap();
            let (p, c) = position(row)?;
            let e = p - led.path.position(t + WINDOW_S / 2.0);
            Some((e.norm_squared(), e.dot(&(c.try_inverse()? * e))))
        })
        .collect()
}

#[test]
fn the_filter_beats_the_windows_and_its_covariance_covers() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulate_moving(&MovingRequest {
        lens: Lens::Two,
        calibration_snr_db: Some(60.0),
        images: 9,
        duration_s: 6.0,
        noise_v: DEFAULT_MOVING_NOISE_V,
        seed: 3,
        out: d.to_path_buf(),
        force: false,
    })
    .unwrap();
    let raw = track(d, TrackFilter::None);
    let cv = track(d, TrackFilter::from_name("cv", None).unwrap());
    assert_eq!(raw.len(), cv.len());
    assert_eq!(raw.len(), 2 * 120);
    for (r, c) in raw.iter().zip(&cv) {
        assert_eq!(r[0], c[0]);
        assert_eq!(c.len(), r.len() + 3);
    }
    let rms = |e: &[(f64, f64)]| (e.iter().map(|x| x.0).sum::<f64>() / e.len() as f64).sqrt();
    let (er, ec) = (errors(&raw), errors(&cv));
    assert!(
        er.len() as f64 >= 0.95 * 2.0 * 110.0,
        "windows with a fix: {}",
        er.len()
    );
    assert!(
        ec.len() as f64 >= 0.95 * 2.0 * 110.0,
        "filtered rows: {}",
        ec.len()
    );
    let (rms_raw, rms_cv) = (rms(&er), rms(&ec));
    let nees = ec.iter().map(|x| x.1).sum::<f64>() / ec.len() as f64;
    let inside =
        ec.iter().filter(|x| x.1 <= 11.344_866_730_144_373).count() as f64 / ec.len() as f64;
    let nees_raw = er.iter().map(|x| x.1).sum::<f64>() / er.len() as f64;
    eprintln!(
        "RMS per window {rms_raw:.2} mm, filtered {rms_cv:.2} mm ({:.2}×); NEES filtered \
         {nees:.2} (per window {nees_raw:.2}); inside 99 %: {:.3}",
        rms_cv / rms_raw,
        inside
    );
    assert!(
        (10.0..=20.0).contains(&rms_raw),
        "per-window RMS {rms_raw} mm"
    );
    assert!(rms_cv <= 0.8 * rms_raw, "{rms_cv} vs {rms_raw}");
    assert!((1.5..=6.0).contains(&nees), "mean NEES {nees}");
    assert!(inside >= 0.9, "inside the 99 % ellipsoid: {inside}");
}
