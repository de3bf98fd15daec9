//! Two reports written into one folder at the same time: each PNG is drawn
//! into a temporary file of its own (`psdcal_io::write_atomic_at`) and
//! renamed, so every PNG is whole whichever report wrote it last, and no
//! temporary file is left behind; the runs take turns on the folder's lock,
//! so neither refuses the other's files.

use std::path::Path;

use psdcal::{write_report, ReportRequest};

fn example(file: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/example")
        .join(file)
}

/// A whole PNG: the signature first, the IEND chunk (with its CRC) last.
fn is_whole_png(bytes: &[u8]) -> bool {
    const SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
    const IEND: &[u8] = b"\0\0\0\0IEND\xaeB`\x82";
    bytes.starts_with(SIGNATURE) && bytes.ends_with(IEND)
}

#[test]
fn two_reports_into_one_folder_leave_whole_pngs_and_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let calibration = dir.path().join("calibration.json");
    let set = psdcal::DataSet::from_files(
        &psdcal::DataSetFiles {
            template: example("template.csv"),
            points: psdcal::PointSource::Observations(example("observations.csv")),
            gains: None,
        },
        &psdcal::LoadOptions::default(),
    )
    .unwrap();
    psdcal::calibrate(&set, &psdcal::CalibrationOptions::default())
        .unwrap()
        .write(&set, &calibration, None)
        .unwrap();
    let out = dir.path().join("report");
    let request = ReportRequest {
        calibration,
        data: Some((example("template.csv"), example("observations.csv"))),
        out: out.clone(),
        limits: Default::default(),
        // Without --force: the second run waits for the first to record its
        // files in the folder's manifest, then finds them psdcal's.
        force: false,
    };
    for _ in 0..100 {
        std::thread::scope(|s| {
            let a = s.spawn(|| write_report(&request));
            let b = s.spawn(|| write_report(&request));
            a.join().unwrap().unwrap();
            b.join().unwrap().unwrap();
        });
        let mut pngs = 0;
        for entry in std::fs::read_dir(&out).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let temporary = name.starts_with('.') && name != psdcal_io::MANIFEST;
            assert!(!temporary, "a temporary file was left: {name}");
            if name.ends_with(".png") {
                assert!(is_whole_png(&std::fs::read(&path).unwrap()), "{name}");
                pngs += 1;
            }
        }
        assert!(pngs >= 4, "only {pngs} PNGs");
    }
}
