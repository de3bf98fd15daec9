//! The live page of `psdcal serve` (`live.html`): one self-contained HTML
//! document (inline CSS and JavaScript, nothing fetched from another host)
//! that reads `/rig` and the Server-Sent Events of `/stream` and draws, on a
//! canvas, a perspective view of the rig rotatable by dragging: each
//! sensor's position, optical axis and field-of-view pyramid (to 1.5 m),
//! each LED with its trail (the last 4 s) and its 95 % ellipsoid (the
//! covariance's principal axes scaled by √χ²₃(0.95) = 2.80, drawn as three
//! ellipses), and a table naming every sensor with its SNR and status per
//! LED, updated as the events come.

/// The page (module documentation).
pub fn live_page() -> &'static str {
    include_str!("live.html")
}
