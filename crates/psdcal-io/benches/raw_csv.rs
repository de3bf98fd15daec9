//! raw.csv read frame by frame (`RawReader`), bytes per second: a
//! recording as `psdcal simulate --raw csv` writes it (`t_s` and four
//! channels of 16-bit codes over ±10 V, the rate from `t_s`), the same
//! channels without `t_s` (`--rate`), and spellings that take the general
//! parser's way for every number (20 significant digits). The input sits in
//! memory behind a 256 KiB buffer, as `RawReader::open` reads a file, so
//! the figure is the parsing alone.
//!
//! Time is the thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`), not the wall
//! clock: the machine is shared, and other work's load would otherwise
//! count.

use std::hint::black_box;
use std::io::{BufReader, Cursor};

use std::time::Duration;

use criterion::measurement::{Measurement, ValueFormatter, WallTime};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use psdcal_io::{write_csv_frames, Frame, RawFormat, RawReader, RAW_CSV_HEADER};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const FRAMES: usize = 200_000;
const RATE: f64 = 20_000.0;

/// The calling thread's CPU time.
struct ThreadCpu;

fn thread_cpu_ns() -> u64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec for clock_gettime to fill.
    let ok = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) } == 0;
    assert!(ok, "no thread CPU clock");
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}

impl Measurement for ThreadCpu {
    type Intermediate = u64;
    type Value = Duration;

    fn start(&self) -> u64 {
        thread_cpu_ns()
    }
    fn end(&self, start: u64) -> Duration {
        Duration::from_nanos(thread_cpu_ns() - start)
    }
    fn add(&self, a: &Duration, b: &Duration) -> Duration {
        *a + *b
    }
    fn zero(&self) -> Duration {
        Duration::ZERO
    }
    fn to_f64(&self, value: &Duration) -> f64 {
        value.as_nanos() as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        // Nanoseconds, shown as the wall clock's are.
        static WALL: WallTime = WallTime;
        WALL.formatter()
    }
}

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

fn bench(c: &mut Criterion<ThreadCpu>) {
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

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(ThreadCpu);
    targets = bench
}
criterion_main!(benches);
