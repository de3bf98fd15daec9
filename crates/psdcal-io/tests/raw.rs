//! Raw recordings, schedules and tones (docs/formats.md): the same frames
//! from raw.csv and raw.npy (float32, float64, either byte order), chunk
//! sizes that do not matter, and a clear error naming the file (and the row)
//! for every bad input; mutation fuzzing of the three readers with a fixed
//! seed (`PSDCAL_FUZZ_CASES` cases per seed file, default 150).

use std::io::Cursor;

use psdcal_io::{Frame, IoError, RawFormat, RawReader, Schedule, Tones};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn frames(n: usize) -> Vec<Frame> {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    // Values exact in float32, so both dtypes give the same f64.
    (0..n)
        .map(|_| std::array::from_fn(|_| (rng.random_range(-9.0f32..9.0)) as f64))
        .collect()
}

fn csv_text(frames: &[Frame], rate: Option<f64>) -> String {
    let mut s = String::from("# a comment\n");
    s += if rate.is_some() {
        "t_s,vy2,vx1,vx2,vy1,extra\n"
    } else {
        "vy2,vx1,vx2,vy1\n"
    };
    for (n, f) in frames.iter().enumerate() {
        match rate {
            Some(r) => s += &format!("{},{},{},{},{},x\n", n as f64 / r, f[3], f[0], f[1], f[2]),
            None => s += &format!("{},{},{},{}\n", f[3], f[0], f[1], f[2]),
        }
    }
    s
}

fn npy_bytes(frames: &[Frame], descr: &str, fortran: bool, shape: &str) -> Vec<u8> {
    let dict = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
        if fortran { "True" } else { "False" }
    );
    let mut header = dict.into_bytes();
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(b' ');
    }
    header.push(b'\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(&header);
    for f in frames {
        for &v in f {
            match descr {
                "<f8" => out.extend_from_slice(&v.to_le_bytes()),
                ">f8" => out.extend_from_slice(&v.to_be_bytes()),
                "<f4" => out.extend_from_slice(&(v as f32).to_le_bytes()),
                ">f4" => out.extend_from_slice(&(v as f32).to_be_bytes()),
                _ => out.extend_from_slice(&(v as i32).to_le_bytes()),
            }
        }
    }
    out
}

fn read_all(
    source: &str,
    format: RawFormat,
    bytes: Vec<u8>,
    rate: Option<f64>,
    chunk: usize,
) -> Result<(Vec<Frame>, f64), IoError> {
    let mut reader = RawReader::from_reader(source, format, Cursor::new(bytes), rate)?;
    let mut out = Vec::new();
    while reader.read_frames(&mut out, chunk)? > 0 {}
    Ok((out, reader.sample_rate_hz()))
}

fn error(result: Result<(Vec<Frame>, f64), IoError>) -> String {
    let e = result.expect_err("expected an error");
    let text = e.to_string();
    assert!(text.starts_with("raw."), "{text}");
    assert!(!text.contains('\n'), "{text}");
    text
}

#[test]
fn csv_and_npy_give_the_same_frames() {
    let want = frames(1000);
    for chunk in [1, 7, 256, 5000] {
        let (got, rate) = read_all(
            "raw.csv",
            RawFormat::Csv,
            csv_text(&want, Some(20_000.0)).into_bytes(),
            None,
            chunk,
        )
        .unwrap();
        assert_eq!(got, want);
        assert!((rate - 20_000.0).abs() < 1e-6, "{rate}");
        let (got, rate) = read_all(
            "raw.csv",
            RawFormat::Csv,
            csv_text(&want, None).into_bytes(),
            Some(5000.0),
            chunk,
        )
        .unwrap();
        assert_eq!(got, want);
        assert_eq!(rate, 5000.0);
        for descr in ["<f8", ">f8", "<f4", ">f4"] {
            let bytes = npy_bytes(&want, descr, false, "(1000, 4)");
            let (got, _) =
                read_all("raw.npy", RawFormat::Npy, bytes, Some(20_000.0), chunk).unwrap();
            assert_eq!(got, want, "{descr}");
        }
    }
}

#[test]
fn bad_recordings_are_clear_errors() {
    let want = frames(50);
    let npy = |bytes: Vec<u8>| read_all("raw.npy", RawFormat::Npy, bytes, Some(1000.0), 16);
    assert!(error(npy(npy_bytes(&want, "<i4", false, "(50, 4)"))).contains("dtype '<i4'"));
    assert!(error(npy(npy_bytes(&want, "<f8", true, "(50, 4)"))).contains("Fortran order"));
    assert!(error(npy(npy_bytes(&want, "<f8", false, "(100, 2)"))).contains("expected (N, 4)"));
    assert!(error(npy(npy_bytes(&want, "<f8", false, "(200,)"))).contains("expected (N, 4)"));
    let mut truncated = npy_bytes(&want, "<f8", false, "(50, 4)");
    truncated.truncate(truncated.len() - 40);
    assert!(error(npy(truncated)).contains("truncated at sample row 48"));
    let mut extra = npy_bytes(&want, "<f8", false, "(50, 4)");
    extra.push(0);
    assert!(error(npy(extra)).contains("bytes after"));
    let mut nan = want.clone();
    nan[7][2] = f64::NAN;
    assert!(error(npy(npy_bytes(&nan, "<f8", false, "(50, 4)"))).contains("sample row 7"));
    assert!(error(npy(b"\x93NUMPY\x01".to_vec())).contains("header"));
    assert!(error(npy(b"PK\x03\x04 not numpy".to_vec())).contains("magic"));
    assert!(error(read_all(
        "raw.npy",
        RawFormat::Npy,
        npy_bytes(&want, "<f8", false, "(50, 4)"),
        None,
        8
    ))
    .contains("--rate"));

    let csv = |text: String, rate| read_all("raw.csv", RawFormat::Csv, text.into_bytes(), rate, 16);
    assert!(error(csv(csv_text(&want, None), None)).contains("t_s"));
    assert!(error(csv("vx1,vx2,vy1\n1,2,3\n".into(), Some(10.0))).contains("missing column 'vy2'"));
    let mut gap = csv_text(&want, Some(1000.0));
    gap = gap.replace("\n0.01,", "\n0.0115,");
    let text = error(csv(gap, None));
    assert!(text.starts_with("raw.csv:13:"), "{text}");
    let text = error(csv(
        "t_s,vx1,vx2,vy1,vy2\n0,1,1,1,1\n0.001,1,nan,1,1\n".into(),
        None,
    ));
    assert!(
        text.starts_with("raw.csv:3:") && text.contains("vx2"),
        "{text}"
    );
    assert!(error(csv(csv_text(&want, None), Some(-5.0))).contains("--rate"));
    // t_s and --rate must agree.
    assert!(error(csv(csv_text(&want, Some(1000.0)), Some(1100.0))).contains("step"));
}

#[test]
fn schedules_and_tones_are_checked() {
    let s = Schedule::from_str(
        "schedule.csv",
        "image,led,t_start_s,t_stop_s\n2,b,0.2,0.3\n1,a,0,0.1\n",
    )
    .unwrap();
    assert!(s.time_multiplexed);
    assert_eq!(s.rows[0].led.as_deref(), Some("a"));
    let e = Schedule::from_str(
        "schedule.csv",
        "image,t_start_s,t_stop_s\n1,0,0.2\n2,0.1,0.3\n",
    )
    .unwrap_err();
    assert!(
        e.to_string().starts_with("schedule.csv:3:") && e.to_string().contains("line 2"),
        "{e}"
    );
    let e =
        Schedule::from_str("schedule.csv", "image,t_start_s,t_stop_s\n1,0.2,0.2\n").unwrap_err();
    assert!(e.to_string().contains("t_stop_s"), "{e}");
    let e = Schedule::from_str("schedule.csv", "image,t_start_s,t_stop_s\n1,-1,0.2\n").unwrap_err();
    assert!(e.to_string().contains("t_start_s"), "{e}");
    let t = Tones::from_str("tones.csv", "led,frequency_hz\na,900\nb,1000\n").unwrap();
    assert_eq!(t.tones[1].frequency_hz, 1000.0);
    let e = Tones::from_str("tones.csv", "led,frequency_hz\na,900\na,1000\n").unwrap_err();
    assert!(e.to_string().contains("twice"), "{e}");
    let e = Tones::from_str("tones.csv", "led,frequency_hz\na,0\n").unwrap_err();
    assert!(e.to_string().starts_with("tones.csv:2:"), "{e}");
}

fn cases() -> usize {
    std::env::var("PSDCAL_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(150)
}

/// One mutation: bytes flipped, inserted, deleted, cut, or hostile tokens.
fn mutate(seed: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    const TOKENS: &[&str] = &[
        "nan",
        "1e999",
        "-inf",
        ",",
        "\n",
        "\"",
        "\0",
        "\r",
        "'shape': (3, 4)",
        "True",
        "<i8",
        ")",
        "99999999999999999999",
    ];
    let mut b = seed.to_vec();
    for _ in 0..rng.random_range(1..4) {
        let at = rng.random_range(0..b.len().max(1)).min(b.len());
        match rng.random_range(0..5) {
            0 if !b.is_empty() => {
                let i = at.min(b.len() - 1);
                b[i] ^= 1 << rng.random_range(0..8);
            }
            1 => {
                let token = TOKENS[rng.random_range(0..TOKENS.len())];
                b.splice(at..at, token.bytes());
            }
            2 => {
                let end = (at + rng.random_range(1..40)).min(b.len());
                b.drain(at..end);
            }
            3 => b.truncate(at),
            _ => b.insert(at, rng.random::<u8>()),
        }
    }
    b
}

#[test]
fn mutated_raw_files_never_panic_and_errors_name_the_file() {
    let want = frames(40);
    let seeds: Vec<(&str, RawFormat, Vec<u8>, Option<f64>)> = vec![
        (
            "raw.csv",
            RawFormat::Csv,
            csv_text(&want, Some(1000.0)).into_bytes(),
            None,
        ),
        (
            "raw.csv",
            RawFormat::Csv,
            csv_text(&want, None).into_bytes(),
            Some(1000.0),
        ),
        (
            "raw.npy",
            RawFormat::Npy,
            npy_bytes(&want, "<f8", false, "(40, 4)"),
            Some(1000.0),
        ),
        (
            "raw.npy",
            RawFormat::Npy,
            npy_bytes(&want, ">f4", false, "(40, 4)"),
            Some(1000.0),
        ),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    for (source, format, seed, rate) in &seeds {
        for _ in 0..cases() {
            let bytes = mutate(seed, &mut rng);
            match read_all(source, *format, bytes, *rate, 1 + rng.random_range(0..64)) {
                Ok((frames, rate)) => {
                    assert!(rate.is_finite() && rate > 0.0);
                    assert!(frames.iter().flatten().all(|v| v.is_finite()));
                }
                Err(e) => {
                    let text = e.to_string();
                    assert!(text.starts_with(source), "{text}");
                    assert!(
                        !text.contains('\n') && text.chars().count() <= 600,
                        "{text}"
                    );
                }
            }
        }
    }
    let schedule = "image,led,t_start_s,t_stop_s\n1,a,0,0.1\n1,b,0.1,0.2\n2,a,0.25,0.3\n";
    let tones = "led,frequency_hz\na,900\nb,1000\n";
    for _ in 0..cases() {
        let bytes = mutate(schedule.as_bytes(), &mut rng);
        if let Ok(text) = String::from_utf8(bytes) {
            match Schedule::from_str("schedule.csv", &text) {
                Ok(s) => assert!(s
                    .rows
                    .iter()
                    .all(|r| r.t_start_s.is_finite() && r.t_stop_s > r.t_start_s)),
                Err(e) => assert!(e.to_string().starts_with("schedule.csv"), "{e}"),
            }
        }
        let bytes = mutate(tones.as_bytes(), &mut rng);
        if let Ok(text) = String::from_utf8(bytes) {
            match Tones::from_str("tones.csv", &text) {
                Ok(t) => assert!(t
                    .tones
                    .iter()
                    .all(|t| t.frequency_hz.is_finite() && t.frequency_hz > 0.0)),
                Err(e) => assert!(e.to_string().starts_with("tones.csv"), "{e}"),
            }
        }
    }
}
