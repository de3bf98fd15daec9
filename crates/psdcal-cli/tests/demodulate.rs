//! `psdcal demodulate` from the command line: simulate a raw recording,
//! demodulate it (text and JSON summaries), and every bad input — a
//! schedule outside the recording, overlapping intervals, a wrong .npy,
//! tones too close for the window, a saturated record, an output over an
//! input — a clear message naming the file (and line), never a panic.

mod common;

use std::path::Path;

use common::{psdcal, stderr, stdout};

fn simulate(dir: &Path, extra: &[&str]) {
    let mut args = vec![
        "-q", "simulate", "--snr", "40", "--images", "3", "--seed", "4", "--out",
    ];
    args.push(dir.to_str().unwrap());
    args.extend_from_slice(extra);
    let run = psdcal(&args);
    assert!(run.status.success(), "{}", stderr(&run));
}

fn demodulate(dir: &Path, raw: &str, schedule: &str, extra: &[&str]) -> std::process::Output {
    let p = |f: &str| dir.join(f).display().to_string();
    let mut args = vec![
        "demodulate".to_string(),
        "--raw".into(),
        p(raw),
        "--schedule".into(),
        p(schedule),
        "--out".into(),
        p("out.csv"),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    psdcal(&args)
}

#[test]
fn demodulates_a_simulated_recording() {
    let dir = tempfile::tempdir().unwrap();
    simulate(dir.path(), &["--raw", "csv"]);
    let run = demodulate(dir.path(), "raw.csv", "schedule.csv", &[]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(
        stdout(&run).contains("demodulated 42 records (ok 42)"),
        "{}",
        stdout(&run)
    );
    let text = std::fs::read_to_string(dir.path().join("out.csv")).unwrap();
    assert!(text.lines().nth(1).unwrap() == "image,led,vx1,vx2,vy1,vy2,snr_db");
    assert_eq!(text.lines().count(), 44);
    // calibrate reads it (snr_db is an extra column).
    let cal = dir.path().join("cal.json");
    let run = psdcal([
        "-q",
        "calibrate",
        "-t",
        dir.path().join("template.csv").to_str().unwrap(),
        "-s",
        dir.path().join("out.csv").to_str().unwrap(),
        "--out",
        cal.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));

    // Frequency multiplexing, npy, JSON summary.
    let fdma = dir.path().join("fdma");
    simulate(&fdma, &["--raw", "npy", "--fdma"]);
    let run = demodulate(
        &fdma,
        "raw.npy",
        "schedule.csv",
        &[
            "--rate",
            "20000",
            "--tones",
            fdma.join("tones.csv").to_str().unwrap(),
            "--json",
        ],
    );
    assert!(run.status.success(), "{}", stderr(&run));
    let json: serde_json::Value = serde_json::from_str(&stdout(&run)).unwrap();
    assert_eq!(json["written"], 42);
    assert_eq!(json["records"], 42);
    assert!(json["snr_db"]["median"].as_f64().unwrap() > 15.0);
}

#[test]
fn bad_inputs_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulate(d, &["--raw", "npy", "--impairments", "none"]);
    let write = |name: &str, text: &str| std::fs::write(d.join(name), text).unwrap();
    // Without --rate a .npy has no sample rate.
    let run = demodulate(d, "raw.npy", "schedule.csv", &[]);
    assert_eq!(run.status.code(), Some(1));
    assert!(
        stderr(&run).contains("raw.npy") && stderr(&run).contains("--rate"),
        "{}",
        stderr(&run)
    );
    // A sample rate below twice the modulation frequency (a wrong --rate).
    let run = demodulate(d, "raw.npy", "schedule.csv", &["--rate", "1500"]);
    assert_eq!(run.status.code(), Some(1));
    let err = stderr(&run);
    assert!(
        err.contains("schedule.csv:") && err.contains("Nyquist"),
        "{err}"
    );
    assert!(err.contains("is the sample rate right?"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    // An interval past the end.
    write(
        "late.csv",
        "image,led,t_start_s,t_stop_s\n1,1,0,0.065\n1,2,100,100.065\n",
    );
    let run = demodulate(d, "raw.npy", "late.csv", &["--rate", "20000"]);
    assert_eq!(run.status.code(), Some(1));
    assert!(
        stderr(&run).contains("late.csv:3") && stderr(&run).contains("ends after the recording"),
        "{}",
        stderr(&run)
    );
    // Overlapping intervals.
    write(
        "overlap.csv",
        "image,led,t_start_s,t_stop_s\n1,1,0,0.065\n1,2,0.06,0.13\n",
    );
    let run = demodulate(d, "raw.npy", "overlap.csv", &["--rate", "20000"]);
    assert!(
        stderr(&run).contains("overlap.csv:3") && stderr(&run).contains("line 2"),
        "{}",
        stderr(&run)
    );
    // Too short, and tones too close for the window: statuses, not errors.
    write(
        "short.csv",
        "image,t_start_s,t_stop_s\n1,0,0.01\n2,0.065,0.13\n",
    );
    write("close.csv", "led,frequency_hz\na,1000\nb,1010\n");
    let run = demodulate(
        d,
        "raw.npy",
        "short.csv",
        &[
            "--rate",
            "20000",
            "--tones",
            d.join("close.csv").to_str().unwrap(),
            "--json",
        ],
    );
    assert!(run.status.success(), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(
        err.contains("short.csv:2") && err.contains("too_short"),
        "{err}"
    );
    assert!(
        err.contains("short.csv:3") && err.contains("tone_collision"),
        "{err}"
    );
    let json: serde_json::Value = serde_json::from_str(&stdout(&run)).unwrap();
    assert_eq!(json["written"], 0);
    assert_eq!(json["status"]["too_short"], 2);
    assert_eq!(json["status"]["tone_collision"], 2);
    // A saturated record: full scale below the signal.
    let run = demodulate(
        d,
        "raw.npy",
        "schedule.csv",
        &["--rate", "20000", "--full-scale", "0.05"],
    );
    assert!(run.status.success());
    assert!(stderr(&run).contains("saturated"), "{}", stderr(&run));
    // A wrong .npy.
    let mut bytes = std::fs::read(d.join("raw.npy")).unwrap();
    let at = bytes.windows(3).position(|w| w == b"<f8").unwrap();
    bytes[at + 1] = b'i';
    std::fs::write(d.join("int.npy"), &bytes).unwrap();
    let run = demodulate(d, "int.npy", "schedule.csv", &["--rate", "20000"]);
    assert!(
        stderr(&run).contains("int.npy") && stderr(&run).contains("dtype '<i8'"),
        "{}",
        stderr(&run)
    );
    // The output may not be an input.
    let p = |f: &str| d.join(f).display().to_string();
    let run = psdcal([
        "demodulate",
        "--raw",
        &p("raw.npy"),
        "--rate",
        "20000",
        "--schedule",
        &p("schedule.csv"),
        "--out",
        &p("schedule.csv"),
    ]);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
}

/// `track` answers each window as soon as its samples have arrived: the
/// first angles come out while the input is still open.
#[test]
fn track_answers_before_the_input_ends() {
    use std::io::{BufRead, BufReader, Write};
    use std::process::{Command, Stdio};
    use std::sync::mpsc;
    use std::time::Duration;

    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulate(d, &["--raw", "csv", "--fdma"]);
    let p = |f: &str| d.join(f).display().to_string();
    let run = psdcal([
        "-q",
        "calibrate",
        "-t",
        &p("template.csv"),
        "-s",
        &p("signals.csv"),
        "--out",
        &p("cal.json"),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let mut child = Command::new(env!("CARGO_BIN_EXE_psdcal"))
        .args([
            "-q",
            "track",
            "--calibration",
            &p("cal.json"),
            "--rate",
            "20000",
            "--tones",
            &p("tones.csv"),
            "--window",
            "0.065",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines() {
            if tx.send(line.unwrap()).is_err() {
                break;
            }
        }
    });
    let mut stdin = child.stdin.take().unwrap();
    let raw = std::fs::read_to_string(d.join("raw.csv")).unwrap();
    let rows: Vec<&str> = raw.lines().filter(|l| !l.starts_with('#')).collect();
    // The header (t_s is an extra column) and one window of samples.
    for line in &rows[..=1300] {
        writeln!(stdin, "{line}").unwrap();
    }
    stdin.flush().unwrap();
    let header = rx.recv_timeout(Duration::from_secs(20)).unwrap();
    assert_eq!(header, "t_s,led,alpha_x_deg,alpha_y_deg,snr_db,status");
    let first = rx
        .recv_timeout(Duration::from_secs(20))
        .expect("a row before the input ends");
    assert!(
        first.starts_with("0,1,") && first.ends_with(",ok"),
        "{first}"
    );
    drop(stdin);
    assert!(child.wait().unwrap().success());
    let rest: Vec<String> = rx.iter().collect();
    assert_eq!(rest.len(), 13, "{rest:?}");
}
