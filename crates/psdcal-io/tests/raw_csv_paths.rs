//! raw.csv's numeric fast path against the general CSV reader: on randomly
//! generated files (seeded, ChaCha8 per case) with varied number spellings
//! (exponents, signs, a leading `+`, many digits, integers, `5.`, `.5`),
//! blanks around fields, LF and CRLF, header variants (column order, case,
//! quoted names, extra columns, comments, a byte-order mark, with and
//! without `t_s`) and injected faults (NaN, infinities, empty cells, a
//! field too many or too few, junk, quotes, comments and blank lines
//! between rows, control bytes, non-UTF-8 bytes, a gap in `t_s`), the same
//! frames to the bit and the same error (file, line, column, message).
//!
//! The general reader alone is the reference: a read buffer of one byte
//! never holds a whole line, so the fast path takes none (checked with
//! [`RawReader::fast_rows`]). The fast reader reads the whole input from
//! one buffer (a `Cursor`), and mixed readers use small buffers, where
//! lines cut by the buffer's end go to the general reader.

use std::io::{BufReader, Cursor};

use psdcal_io::{Frame, RawFormat, RawReader};
use rand::seq::{IndexedRandom, SliceRandom};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const CASES: u64 = 1500;

/// What a read gave: the frames handed out (also those before an error),
/// the rate, the error's text, and how many rows the fast path took.
#[derive(Debug)]
struct Outcome {
    frames: Vec<[u64; 4]>,
    rate_bits: Option<u64>,
    error: Option<String>,
    fast_rows: u64,
}

fn read<R: std::io::BufRead + 'static>(reader: R, rate: Option<f64>, chunks: &[usize]) -> Outcome {
    let mut out: Vec<Frame> = Vec::new();
    let bits = |out: &[Frame]| out.iter().map(|f| f.map(f64::to_bits)).collect();
    let mut raw = match RawReader::from_reader("raw.csv", RawFormat::Csv, reader, rate) {
        Ok(raw) => raw,
        Err(e) => {
            return Outcome {
                frames: Vec::new(),
                rate_bits: None,
                error: Some(e.to_string()),
                fast_rows: 0,
            }
        }
    };
    let mut k = 0;
    loop {
        let chunk = chunks[k % chunks.len()];
        k += 1;
        match raw.read_frames(&mut out, chunk) {
            Ok(0) => break,
            Ok(_) => {}
            Err(e) => {
                return Outcome {
                    frames: bits(&out),
                    rate_bits: Some(raw.sample_rate_hz().to_bits()),
                    error: Some(e.to_string()),
                    fast_rows: raw.fast_rows(),
                }
            }
        }
    }
    Outcome {
        frames: bits(&out),
        rate_bits: Some(raw.sample_rate_hz().to_bits()),
        error: None,
        fast_rows: raw.fast_rows(),
    }
}

/// A number spelled one of many ways (all read by `str::parse::<f64>`).
fn number(rng: &mut ChaCha8Rng) -> String {
    let magnitude = 10f64.powi(rng.random_range(-12..12));
    let v: f64 = rng.random_range(-1.0..1.0) * magnitude;
    match rng.random_range(0..14) {
        0 => format!("{v}"),
        1 => format!("{v:e}"),
        2 => format!("{v:E}"),
        3 => format!("{v:+}"),
        4 => format!("{v:.3}"),
        5 => format!("{v:.17}"),
        6 => format!("{v:.25}"),
        7 => format!("{}", rng.random_range(-100_000i64..100_000)),
        8 => format!(
            "{:+}e{:+}",
            rng.random_range(-999i64..999),
            rng.random_range(-30..30)
        ),
        9 => format!("{}.", rng.random_range(0..1000)),
        10 => format!(
            "{}.{:0width$}",
            if rng.random_bool(0.5) { "-" } else { "" },
            rng.random_range(0..1_000_000u64),
            width = 6
        ),
        11 => format!("000{}", (v * 1e3).abs()),
        // 16-bit codes over ±10 V, as a card writes them.
        12 => format!(
            "{}",
            f64::from(rng.random_range(-32768i32..32768)) * (10.0 / 32768.0)
        ),
        _ => format!(
            "{}{}",
            rng.random_range(1..10u64),
            (0..rng.random_range(10..30))
                .map(|_| char::from(b'0' + rng.random_range(0..10u8)))
                .collect::<String>()
        ),
    }
}

fn blank(rng: &mut ChaCha8Rng) -> &'static str {
    match rng.random_range(0..10) {
        0 => " ",
        1 => "\t",
        2 => "  \t ",
        _ => "",
    }
}

/// A fault that replaces a field's text.
fn bad_field(rng: &mut ChaCha8Rng) -> String {
    [
        "nan",
        "NaN",
        "inf",
        "-inf",
        "+infinity",
        "",
        "  ",
        "1e999",
        "-1e400",
        "abc",
        "1.2.3",
        "1e",
        "--1",
        "\"1.5\"",
        " \"2\" ",
        "1 2",
        "0x10",
        "1_000",
        "\u{a0}1.5",
        "1.5\u{2003}",
        "é",
        "1,5",
    ]
    .choose(rng)
    .unwrap()
    .to_string()
}

/// One generated raw.csv and the rate to read it with.
fn case(seed: u64) -> (Vec<u8>, Option<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let with_time = rng.random_bool(0.6);
    let extras = rng.random_range(0..3);
    let mut columns: Vec<&str> = vec!["vx1", "vx2", "vy1", "vy2"];
    if with_time {
        columns.push("t_s");
    }
    columns.extend(["note", "extra"].iter().take(extras));
    columns.shuffle(&mut rng);
    let faulty = rng.random_bool(0.5);
    let fault_rate = if faulty { 0.02 } else { 0.0 };
    let mut text = String::new();
    let mut bytes_prefix: Vec<u8> = Vec::new();
    if rng.random_bool(0.1) {
        bytes_prefix.extend_from_slice(b"\xEF\xBB\xBF");
    }
    if rng.random_bool(0.5) {
        text += "# a simulated recording\n\n";
    }
    let header: Vec<String> = columns
        .iter()
        .map(|c| match rng.random_range(0..8) {
            0 => c.to_ascii_uppercase(),
            1 => format!(" {c} "),
            2 => format!("\"{c}\""),
            _ => c.to_string(),
        })
        .collect();
    text += &header.join(",");
    text += "\n";
    let rate: f64 = [20_000.0, 1000.0, 48_000.0, 3.0][rng.random_range(0..4)];
    let time_format = rng.random_range(0..4);
    let rows = rng.random_range(0..80);
    let mut body: Vec<u8> = Vec::new();
    let mut sample = 0u64;
    for _ in 0..rows {
        let crlf = rng.random_bool(0.3);
        let end = if crlf { "\r\n" } else { "\n" };
        if faulty && rng.random_bool(0.02) {
            // A line between rows: comment, blank, only commas, junk.
            let line = ["# c", "", "   ", ",,,,,", "\t#x", "x"][rng.random_range(0..6)];
            body.extend_from_slice(format!("{line}{end}").as_bytes());
            continue;
        }
        if faulty && rng.random_bool(0.01) {
            sample += 2; // a gap in t_s
        }
        let t = sample as f64 / rate;
        sample += 1;
        let texts: Vec<String> = columns
            .iter()
            .map(|c| match *c {
                "t_s" => match time_format {
                    0 => format!("{t}"),
                    1 => format!("{t:e}"),
                    2 => format!("{t:.9}"),
                    _ => format!("{t:+.12}"),
                },
                "note" => ["", "ok", "a b", "#1", "x-y.z", "q'"][rng.random_range(0..6)].into(),
                "extra" => number(&mut rng),
                _ => number(&mut rng),
            })
            .collect();
        let mut fields: Vec<String> = texts
            .into_iter()
            .map(|f| {
                if rng.random_bool(fault_rate) {
                    bad_field(&mut rng)
                } else {
                    format!("{}{f}{}", blank(&mut rng), blank(&mut rng))
                }
            })
            .collect();
        if rng.random_bool(fault_rate) {
            match rng.random_range(0..4) {
                0 => {
                    fields.pop();
                }
                1 => fields.push(String::new()),
                2 => fields.push(" 1".into()),
                _ => fields.push("  ".into()),
            }
        }
        let mut line = fields.join(",").into_bytes();
        if rng.random_bool(fault_rate / 2.0) {
            let at = rng.random_range(0..=line.len());
            let byte = [b'\x01', b'\r', b'\xff', b'\x7f', b'\0'][rng.random_range(0..5)];
            line.insert(at, byte);
        }
        body.extend_from_slice(&line);
        body.extend_from_slice(end.as_bytes());
    }
    if rng.random_bool(0.3) {
        // No line end after the last row.
        while body.last().is_some_and(|b| *b == b'\n' || *b == b'\r') {
            body.pop();
        }
    }
    let given_rate = match (with_time, rng.random_range(0..4)) {
        (true, 0 | 1) => None,
        (_, 3) if faulty => Some(rate * 1.01),
        _ => Some(rate),
    };
    let mut bytes = bytes_prefix;
    bytes.extend_from_slice(text.as_bytes());
    bytes.extend_from_slice(&body);
    (bytes, given_rate)
}

#[test]
fn fast_and_general_paths_agree_on_random_files() {
    let mut fast_rows = 0u64;
    let mut rows = 0u64;
    let mut errors = std::collections::BTreeSet::new();
    let mut column_errors = 0;
    for seed in 0..CASES {
        let (bytes, rate) = case(seed);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
        let chunks: Vec<usize> = (0..3).map(|_| rng.random_range(1..40)).collect();
        let general = read(
            BufReader::with_capacity(1, Cursor::new(bytes.clone())),
            rate,
            &chunks,
        );
        assert_eq!(general.fast_rows, 0, "seed {seed}");
        let fast = read(Cursor::new(bytes.clone()), rate, &chunks);
        let capacity = rng.random_range(2..300);
        let mixed = read(
            BufReader::with_capacity(capacity, Cursor::new(bytes.clone())),
            rate,
            &[rng.random_range(1..1000)],
        );
        let shown = String::from_utf8_lossy(&bytes);
        for (name, other) in [("fast", &fast), ("mixed", &mixed)] {
            assert_eq!(other.error, general.error, "{name}, seed {seed}:\n{shown}");
            assert_eq!(other.rate_bits, general.rate_bits, "{name}, seed {seed}");
            assert_eq!(
                other.frames, general.frames,
                "{name}, seed {seed}:\n{shown}"
            );
        }
        fast_rows += fast.fast_rows;
        rows += fast.frames.len() as u64;
        if let Some(e) = &general.error {
            column_errors += usize::from(e.contains("column"));
            // The kind of error: its message without the location, the
            // numbers and what it quotes.
            let message = e.rsplit(": ").next().unwrap_or("");
            let kind = message.split(['\'', '"']).next().unwrap_or("");
            errors.insert(
                kind.chars()
                    .filter(|c| !c.is_ascii_digit())
                    .take(40)
                    .collect::<String>(),
            );
        }
    }
    // The comparison is not empty: most rows went the fast way, and many
    // kinds of errors were met.
    assert!(fast_rows * 10 > rows * 8, "{fast_rows} of {rows}");
    assert!(column_errors > 50, "{column_errors}");
    assert!(errors.len() > 12, "{errors:#?}");
}

/// The frames of a file psdcal writes come out to the bit, all by the fast
/// path after the first two rows (which give the rate).
#[test]
fn written_recordings_read_back_exactly_and_fast() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let frames: Vec<Frame> = (0..5000)
        .map(|_| std::array::from_fn(|_| rng.random_range(-10.0..10.0)))
        .collect();
    let mut bytes = format!("{}\n", psdcal_io::RAW_CSV_HEADER).into_bytes();
    psdcal_io::write_csv_frames(&mut bytes, 0, 20_000.0, &frames).unwrap();
    let outcome = read(Cursor::new(bytes), None, &[4096]);
    assert_eq!(outcome.error, None);
    let expected: Vec<[u64; 4]> = frames.iter().map(|f| f.map(f64::to_bits)).collect();
    assert_eq!(outcome.frames, expected);
    assert_eq!(outcome.fast_rows, 4998);
}
