//! A JSON file's `format` value is quoted clipped in an error message (a
//! 2 000-character value gives a short line), whatever the kind of file.

use std::fs;

#[test]
fn a_long_format_value_is_clipped_in_every_message() {
    let dir = tempfile::tempdir().unwrap();
    let long = "x".repeat(2000);
    let path = dir.path().join("file.json");
    let bodies = [
        format!(r#"{{"format": "{long}", "version": 1}}"#),
        format!(r#"{{"format": "{long}", "version": 1, "gains": [1, 1, 1]}}"#),
    ];
    for body in &bodies {
        fs::write(&path, body).unwrap();
        let errors = [
            psdcal_io::read_calibration(&path)
                .err()
                .map(|e| e.to_string()),
            psdcal_io::read_gains(&path).err().map(|e| e.to_string()),
            psdcal_io::read_truth(&path).err().map(|e| e.to_string()),
            psdcal_io::read_psd_map(&path).err().map(|e| e.to_string()),
        ];
        for message in errors.into_iter().flatten() {
            assert!(message.len() < 400, "{} chars: {message}", message.len());
        }
    }
}
