//! A reader that went away (`psdcal … | head -1`): every command that
//! prints on standard output ends quietly with status 141 (128 + SIGPIPE,
//! as a shell shows a process a closed pipe ended), never a panic, never
//! an error line; its files are written whole all the same.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};

use common::valid;

/// Runs `psdcal args` in `dir` with standard output a pipe whose reader is
/// already closed: (status, standard error).
fn closed_stdout(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_psdcal"))
        .current_dir(dir)
        .args(args)
        .stdin(Stdio::null())
        .stdout(writer)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn every_command_ends_quietly_with_141_when_its_output_is_closed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let v = |name: &str| valid(name).display().to_string();
    let (t, o, c, p) = (
        v("template.csv"),
        v("observations.csv"),
        v("calibration.json"),
        v("points.csv"),
    );
    let run = |args: &[&str]| {
        let out = common::psdcal(args.iter().map(|a| a.to_string()).collect::<Vec<_>>());
        assert!(out.status.success(), "{args:?}: {}", common::stderr(&out));
    };
    // Inputs for the signal commands.
    let raw = d.join("raw").display().to_string();
    run(&[
        "simulate", "--raw", "csv", "--fdma", "--images", "3", "-q", "--out", &raw,
    ]);
    let commands: Vec<Vec<&str>> = vec![
        vec!["calibrate", "-t", &t, "-o", &o, "--out", "c.json"],
        vec!["check", "-t", &t, "-o", &o],
        vec!["demo"],
        vec!["study", "table2", "--trials", "1", "--out", "study"],
        vec!["report", "-c", &c, "--out", "report"],
        vec![
            "demodulate",
            "--raw",
            "raw/raw.csv",
            "--schedule",
            "raw/schedule.csv",
            "--tones",
            "raw/tones.csv",
            "--out",
            "s.csv",
        ],
        vec!["export", "-c", &c, "--to", "opencv", "--out", "e.yaml"],
        vec!["diff", &c, &c],
        vec!["simulate", "--out", "sim"],
        vec![
            "plan",
            "--template",
            &t,
            "--snr",
            "40",
            "--f",
            "8",
            "--out",
            "p.csv",
        ],
        vec!["aoa", "-c", &c, "-p", &p],
        vec!["correct", "-c", &c, "-p", &p],
        vec!["locate", "-c", &c, "-p", &p, "--distance", "1000"],
        vec!["map", "-c", &c, "--k-sigma", "1"],
        vec![
            "track",
            "--calibration",
            &c,
            "--tones",
            "raw/tones.csv",
            "--raw",
            "raw/raw.csv",
        ],
    ];
    for args in &commands {
        let (status, err) = closed_stdout(d, args);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(!err.contains("error:"), "{args:?}: {err}");
        assert_eq!(status, Some(141), "{args:?}: {err}");
    }
    // The files were written all the same.
    assert!(d.join("c.json").is_file() && d.join("report/report.html").is_file());
}

#[test]
fn a_full_standard_output_is_one_error_line_not_a_panic() {
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        return;
    };
    let t = valid("template.csv").display().to_string();
    let o = valid("observations.csv").display().to_string();
    let out = Command::new(env!("CARGO_BIN_EXE_psdcal"))
        .args(["check", "-t", &t, "-o", &o])
        .stdout(full)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.starts_with("error: standard output: "), "{err}");
    assert!(err.contains("check where standard output goes"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

/// Standard error closed by its reader or full: warnings and errors are
/// lost, never a panic (status 101); the exit status is the command's own.
#[test]
fn a_closed_or_full_standard_error_is_never_a_panic() {
    let t = valid("template.csv").display().to_string();
    let o = valid("observations.csv").display().to_string();
    let dir = tempfile::tempdir().unwrap();
    let off = dir.path().join("off.csv");
    // One point off the sensor: a warning on standard error.
    let text = std::fs::read_to_string(&o).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    let first = lines.iter().position(|l| l.starts_with("image")).unwrap() + 1;
    let image = lines[first].split(',').next().unwrap().to_string();
    let led = lines[first].split(',').nth(1).unwrap().to_string();
    let moved = format!("{image},{led},30,30");
    lines[first] = &moved;
    std::fs::write(&off, lines.join("\n") + "\n").unwrap();
    let off = off.display().to_string();
    let runs: [(&[&str], i32); 3] = [
        (&["check", "-t", &t, "-o", &off], 0),
        (&["check", "-t", &t, "-o", "missing.csv"], 1),
        (&["check", "--no-such-option"], 2),
    ];
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .ok()
    };
    for (args, code) in runs {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let closed = Command::new(env!("CARGO_BIN_EXE_psdcal"))
            .args(args)
            .stdout(Stdio::null())
            .stderr(writer)
            .status()
            .unwrap();
        assert_eq!(
            closed.code(),
            Some(code),
            "{args:?} with standard error closed"
        );
        if let Some(full) = full() {
            let status = Command::new(env!("CARGO_BIN_EXE_psdcal"))
                .args(args)
                .stdout(Stdio::null())
                .stderr(full)
                .status()
                .unwrap();
            assert_eq!(
                status.code(),
                Some(code),
                "{args:?} with standard error full"
            );
        }
    }
}

#[test]
fn track_skips_an_over_long_line_and_reports_a_last_partial_window() {
    use std::io::Write;
    let c = valid("calibration.json").display().to_string();
    let dir = tempfile::tempdir().unwrap();
    let tones = dir.path().join("tones.csv");
    std::fs::write(&tones, "led,frequency_hz\n1,1000\n").unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_psdcal"))
        .args([
            "track",
            "--calibration",
            &c,
            "--tones",
            tones.to_str().unwrap(),
        ])
        .args(["--rate", "20000", "--window", "0.005"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    let sample = |n: usize| -> String {
        (0..n)
            .map(|i| {
                let s = (i as f64 * 0.1 * std::f64::consts::PI).sin();
                format!("{},{},{},{}\n", 1.0 + s, 1.1 + s, 0.9 + s, 1.0 + s)
            })
            .collect()
    };
    // 100 samples (one window), a 3 MiB line, 150 samples: a second window
    // and 50 samples of a third.
    input.write_all(sample(100).as_bytes()).unwrap();
    input.write_all(&vec![b'1'; 3 << 20]).unwrap();
    input.write_all(b"\n").unwrap();
    input.write_all(sample(150).as_bytes()).unwrap();
    drop(input);
    let out = child.wait_with_output().unwrap();
    let (rows, err) = (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    );
    assert!(out.status.success(), "{err}");
    assert_eq!(
        rows.lines()
            .filter(|l| l.ends_with(",line_too_long"))
            .count(),
        1,
        "{rows}"
    );
    assert!(
        err.contains("track: 250 samples, 2 windows, 1 malformed lines"),
        "{err}"
    );
    assert!(
        err.contains("warning: the input ended 50 samples into a window of 100"),
        "{err}"
    );
}
