//! raw.csv read frame by frame (`RawReader`), bytes per second: a
//! recording as `psdcal simulate --raw csv` writes it (`t_s` and four
//! channels of 16-bit codes over ±10 V, the rate from `t_s`), the same
//! channels without `t_s` (`--rate`), and spellings that take the general
//! parser's way for every number (20 significant digits). The input sits in
//! memory behind a 256 KiB buffer, as `RawReader::open` reads a file, so
//! the figure is the parsing alone.

use std::hint::black_box;
use std::io::{BufReader, Cursor};

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use psdcal_io::{write_csv_frames, Frame, RawFormat, RawReader, RAW_CSV_HEADER};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const FRAMES: usize = 200_000;
const RATE: f64 = 20_000.0;

fn codes(n: usize) -> Vec<Frame> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    (0..n)
        .map(|_| {
            std::array::from_fn(|_| f64::from(rng.random_range(-8000i32..8000)) * (10.0 / 32768.0))
        })
        .collect()
}

fn read_all(bytes: &'static [u8], rate: Option<f64>) -> usize {
    let input = BufReader::with_capacity(1 << 18, Cursor::new(bytes));
    let mut reader = RawReader::from_reader("raw.csv", RawFormat::Csv, input, rate).unwrap();
    let mut out = Vec::with_capacity(65_536);
    let mut total = 0;
    loop {
        out.clear();
        let n = reader.read_frames(&mut out, 65_536).unwrap();
        if n == 0 {
            break;
        }
        total += n;
        black_box(&out);
    }
    total
}

fn bench(c: &mut Criterion) {
    let frames = codes(FRAMES);
    let mut timed = format!("{RAW_CSV_HEADER}\n").into_bytes();
    write_csv_frames(&mut timed, 0, RATE, &frames).unwrap();
    let mut untimed = b"vx1,vx2,vy1,vy2\n".to_vec();
    for f in &frames {
        untimed.extend_from_slice(format!("{},{},{},{}\n", f[0], f[1], f[2], f[3]).as_bytes());
    }
    let mut long = b"vx1,vx2,vy1,vy2\n".to_vec();
    for f in &frames {
        long.extend_from_slice(
            format!("{:.19e},{:.19e},{:.19e},{:.19e}\n", f[0], f[1], f[2], f[3]).as_bytes(),
        );
    }
    // Read from memory without a copy per run.
    let [timed, untimed, long]: [&'static [u8]; 3] = [timed, untimed, long].map(|v| &*v.leak());
    let mut group = c.benchmark_group("raw_csv");
    group.sample_size(10);
    for (name, bytes, rate) in [
        ("t_s and 4 channels, as simulate writes", timed, None),
        ("4 channels, --rate", untimed, Some(RATE)),
        ("4 channels, 20 significant digits", long, Some(RATE)),
    ] {
        assert_eq!(read_all(bytes, rate), FRAMES);
        group.throughput(Throughput::Bytes(bytes.len() as u64));
        group.bench_function(name, |b| b.iter(|| read_all(bytes, rate)));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
