//! NI TDMS recordings (docs/formats.md, raw.tdms) against an independent
//! writer and reader: `tests/tdms/make_fixtures.py` wrote each fixture with
//! npTDMS (or byte by byte from NI's layout: the interleaved big-endian
//! file) and, beside it, the values npTDMS's reader finds in it (CSV). The
//! reader must give those values (exactly; 1e-12 relative where a
//! polynomial scale is evaluated), whatever the chunk size; bad files are
//! one-line errors naming the file; mutated files (fixed seed,
//! `PSDCAL_FUZZ_CASES` cases per fixture, default 150) never panic.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use psdcal_io::{Frame, IoError, RawReader, TdmsReader};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/tdms")
        .join(name)
}

/// The values npTDMS read, per row vx1, vx2, vy1, vy2.
fn expected(name: &str) -> Vec<Frame> {
    let text = std::fs::read_to_string(fixture(&format!("{name}.csv"))).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect()
}

fn read(name: &str, channels: &[&str], rate: Option<f64>, chunk: usize) -> (Vec<Frame>, f64) {
    let channels: Vec<String> = channels.iter().map(|c| c.to_string()).collect();
    let mut reader =
        RawReader::open_channels(&fixture(&format!("{name}.tdms")), rate, &channels).unwrap();
    let mut out = Vec::new();
    while reader.read_frames(&mut out, chunk).unwrap() > 0 {}
    (out, reader.sample_rate_hz())
}

fn assert_close(got: &[Frame], want: &[Frame], rel: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: rows");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        for c in 0..4 {
            let tol = rel * w[c].abs();
            assert!(
                (g[c] - w[c]).abs() <= tol,
                "{what}: row {i} channel {c}: {} against npTDMS's {}",
                g[c],
                w[c]
            );
        }
    }
}

#[test]
fn the_values_are_those_nptdms_reads() {
    for chunk in [1, 7, 64, 5000] {
        // Default: the group with vx1..vy2 (written in another order).
        let (got, rate) = read("contiguous_f64", &[], None, chunk);
        assert_close(&got, &expected("contiguous_f64"), 0.0, "contiguous_f64");
        assert!((rate - 20_000.0).abs() < 1e-9, "{rate}");
        // Default: the first four channels, NI linear and polynomial scaling.
        let (got, _) = read("scaled_i16", &[], None, chunk);
        assert_close(&got, &expected("scaled_i16"), 1e-12, "scaled_i16");
        // Named channels in two groups, float32; the rate given agrees.
        let (got, rate) = read(
            "f32_two_groups",
            &["x/vx1", "vx2", "/'y'/'vy1'", "y/vy2"],
            Some(10_000.0),
            chunk,
        );
        assert_close(&got, &expected("f32_two_groups"), 0.0, "f32_two_groups");
        assert_eq!(rate, 10_000.0);
        // Big-endian, interleaved, mixed types, raw-only and incremental segments.
        let (got, _) = read("interleaved_be", &[], None, chunk);
        assert_close(&got, &expected("interleaved_be"), 0.0, "interleaved_be");
    }
}

#[test]
fn the_scaling_is_applied_not_the_raw_counts() {
    // An independent check of the fixture's scale: counts × 10/32768 (+ 0.001 i).
    let want = expected("scaled_i16");
    for row in &want {
        let counts = row[0] / (10.0 / 32768.0);
        assert!((counts - counts.round()).abs() < 1e-6, "{counts}");
        assert!(row[0].abs() <= 10.0);
    }
}

fn open_error(name: &str, channels: &[&str], rate: Option<f64>) -> String {
    let channels: Vec<String> = channels.iter().map(|c| c.to_string()).collect();
    let e = RawReader::open_channels(&fixture(&format!("{name}.tdms")), rate, &channels)
        .expect_err("expected an error");
    let text = e.to_string();
    assert!(text.contains(&format!("{name}.tdms")), "{text}");
    assert!(!text.contains('\n'), "{text}");
    text
}

#[test]
fn bad_files_and_selections_are_clear_errors() {
    let missing = open_error(
        "contiguous_f64",
        &["psd/vx1", "psd/vx2", "psd/vy1", "psd/vz"],
        None,
    );
    assert!(missing.contains("no channel 'psd/vz'"), "{missing}");
    assert!(missing.contains("psd/temperature"), "{missing}");
    let few = open_error("contiguous_f64", &["vx1", "vx2"], None);
    assert!(few.contains("expected four"), "{few}");
    let rate = open_error("contiguous_f64", &[], Some(1000.0));
    assert!(rate.contains("wf_increment"), "{rate}");
    let strings = {
        let channels: Vec<String> = ["vx1", "vx2", "vy1", "note"].map(String::from).to_vec();
        let mut r =
            RawReader::open_channels(&fixture("contiguous_f64.tdms"), None, &channels).unwrap();
        r.read_frames(&mut Vec::new(), 1000)
            .unwrap_err()
            .to_string()
    };
    // The string channel: values only in later segments, and strings.
    assert!(strings.contains("channel psd/note"), "{strings}");
    // A file with too few channels for the default.
    let bytes = std::fs::read(fixture("f32_two_groups.tdms")).unwrap();
    let e = TdmsReader::from_reader("f.tdms", Cursor::new(bytes.clone()), &[], 8).unwrap_err();
    assert!(e.to_string().contains("holds 4 channels"), "{e}");
    // Truncated: the segment announces more bytes than the file holds.
    let cut = tdms_error("cut.tdms", bytes[..bytes.len() - 10].to_vec());
    assert!(cut.contains("truncated"), "{cut}");
    let lead = tdms_error("lead.tdms", bytes[..20].to_vec());
    assert!(lead.contains("truncated"), "{lead}");
    let mut not = bytes.clone();
    not[..4].copy_from_slice(b"PK\x03\x04");
    assert!(tdms_error("zip.tdms", not).contains("TDSm"));
    // A channel without a sample rate, no --rate.
    let mut no_rate = bytes;
    while let Some(at) = find(&no_rate, b"wf_increment") {
        no_rate[at] = b'W';
    }
    let e = TdmsReader::from_reader("r.tdms", Cursor::new(no_rate), &[], 4).unwrap();
    let e = RawReader::from_tdms(e, &[], None).unwrap_err().to_string();
    assert!(e.contains("--rate"), "{e}");
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

fn read_bytes(source: &str, bytes: Vec<u8>, chunk: usize) -> Result<Vec<f64>, IoError> {
    let mut r = TdmsReader::from_reader(source, Cursor::new(bytes), &[], 4)?;
    r.increment_s(1e-3)?;
    let mut out = Vec::new();
    while r.read_rows(&mut out, chunk)? > 0 {}
    Ok(out)
}

fn tdms_error(source: &str, bytes: Vec<u8>) -> String {
    let text = read_bytes(source, bytes, 64).unwrap_err().to_string();
    assert!(text.starts_with(source), "{text}");
    assert!(!text.contains('\n'), "{text}");
    text
}

/// One mutation: bits flipped, hostile 32-bit values over fields, bytes
/// inserted or deleted, the file cut.
fn mutate(seed: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    const WORDS: &[u32] = &[
        0,
        1,
        20,
        28,
        0xFFFF_FFFF,
        0x7FFF_FFFF,
        0x6912_0000,
        0x20,
        0x44,
        4713,
    ];
    let mut b = seed.to_vec();
    for _ in 0..rng.random_range(1..4) {
        let at = rng.random_range(0..b.len().max(1)).min(b.len());
        match rng.random_range(0..5) {
            0 if !b.is_empty() => {
                let i = at.min(b.len() - 1);
                b[i] ^= 1 << rng.random_range(0..8);
            }
            1 if at + 4 <= b.len() => {
                let w = WORDS[rng.random_range(0..WORDS.len())];
                let bytes = if rng.random() {
                    w.to_le_bytes()
                } else {
                    w.to_be_bytes()
                };
                b[at..at + 4].copy_from_slice(&bytes);
            }
            2 => {
                let end = (at + rng.random_range(1..16)).min(b.len());
                b.drain(at..end);
            }
            3 => b.truncate(at),
            _ => b.insert(at, rng.random::<u8>()),
        }
    }
    b
}

#[test]
fn mutated_tdms_files_never_panic_and_errors_name_the_file() {
    let cases: usize = std::env::var("PSDCAL_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(150);
    let mut rng = ChaCha8Rng::seed_from_u64(4712);
    for name in [
        "contiguous_f64",
        "scaled_i16",
        "f32_two_groups",
        "interleaved_be",
    ] {
        let seed = std::fs::read(fixture(&format!("{name}.tdms"))).unwrap();
        for _ in 0..cases {
            let bytes = mutate(&seed, &mut rng);
            let chunk = 1 + rng.random_range(0..100);
            match read_bytes("raw.tdms", bytes, chunk) {
                Ok(values) => assert!(values.iter().all(|v| v.is_finite())),
                Err(e) => {
                    let text = e.to_string();
                    assert!(text.starts_with("raw.tdms"), "{text}");
                    assert!(
                        !text.contains('\n') && text.chars().count() <= 600,
                        "{text}"
                    );
                }
            }
        }
    }
}
