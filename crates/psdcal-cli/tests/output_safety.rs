//! Nothing lost (issue 33): a folder's files psdcal did not write are never
//! replaced (`--force` replaces them), two outputs written together are
//! renamed together (a full disk, made with RLIMIT_FSIZE, leaves both old
//! files), links are written through, permissions kept, a folder given as
//! `--out` refused clearly, a missing parent folder created.

mod common;

use std::fs;
use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::Command;

use common::{psdcal, stderr, valid};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Asserts a refusal naming `file` and `--force`, with `file` unchanged.
fn assert_refused(out: &std::process::Output, file: &Path, content: &[u8]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(s(file)) && err.contains("--force"), "{err}");
    assert_eq!(fs::read(file).unwrap(), content);
}

#[test]
fn folder_outputs_replace_only_psdcal_s_own_files() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim");
    fs::create_dir(&sim).unwrap();
    let mine = sim.join("observations.csv");
    fs::write(&mine, b"my measurements").unwrap();
    let simulate = |more: &[&str]| {
        let mut args = vec!["simulate", "-q", "--images", "3", "--out", s(&sim)];
        args.extend_from_slice(more);
        psdcal(args)
    };
    let out = simulate(&[]);
    assert_refused(&out, &mine, b"my measurements");
    // Nothing was written: the refusal comes before any file.
    assert!(!sim.join("template.csv").exists());
    // --force replaces; then the folder is psdcal's, and runs again freely.
    assert!(simulate(&["--force"]).status.success());
    assert!(simulate(&[]).status.success());
    assert!(simulate(&["--raw", "csv"]).status.success());
    // A file psdcal wrote but someone edited since is kept too.
    fs::write(sim.join("template.csv"), b"edited").unwrap();
    assert_refused(&simulate(&[]), &sim.join("template.csv"), b"edited");

    // study and report the same way.
    let study = dir.path().join("study");
    fs::create_dir(&study).unwrap();
    fs::write(study.join("study.csv"), b"mine").unwrap();
    let out = psdcal(["study", "table2", "--trials", "1", "-q", "--out", s(&study)]);
    assert_refused(&out, &study.join("study.csv"), b"mine");
    let report = dir.path().join("report");
    fs::create_dir(&report).unwrap();
    fs::write(report.join("report.html"), b"mine").unwrap();
    let c = valid("calibration.json");
    let out = psdcal(["report", "-q", "-c", s(&c), "--out", s(&report)]);
    assert_refused(&out, &report.join("report.html"), b"mine");
    let out = psdcal(["report", "-q", "-c", s(&c), "--out", s(&report), "--force"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = psdcal(["report", "-q", "-c", s(&c), "--out", s(&report)]);
    assert!(out.status.success(), "{}", stderr(&out));

    // simulate-positioning --moving: its recording is refused before any file.
    let moving = dir.path().join("moving");
    fs::create_dir(&moving).unwrap();
    fs::write(moving.join("raw.tdms"), b"mine").unwrap();
    let out = psdcal([
        "simulate-positioning",
        "-q",
        "--moving",
        "0.2",
        "--out",
        s(&moving),
    ]);
    assert_refused(&out, &moving.join("raw.tdms"), b"mine");
    assert!(!moving.join("rig.json").exists());
}

#[test]
fn network_outputs_replace_only_psdcal_s_own_files() {
    let dir = tempfile::tempdir().unwrap();
    let room = dir.path().join("room");
    fs::create_dir(&room).unwrap();
    let mine = room.join("sensors.csv");
    fs::write(&mine, b"my sensors").unwrap();
    let simulate = |more: &[&str]| {
        let mut args = vec![
            "simulate-network",
            "-q",
            "--seconds",
            "4",
            "--out",
            s(&room),
        ];
        args.extend_from_slice(more);
        psdcal(args)
    };
    assert_refused(&simulate(&[]), &mine, b"my sensors");
    assert!(!room.join("wand.csv").exists());
    assert!(simulate(&["--force"]).status.success());
    assert!(simulate(&[]).status.success());
    // The refined calibrations beside rig.json and the report page.
    let f = |name: &str| room.join(name);
    let calibrate = |more: &[&str]| {
        let (sensors, wand, frame) = (f("sensors.csv"), f("wand.csv"), f("frame.csv"));
        let (points, rig, report) = (f("network_points.csv"), f("out/rig.json"), f("page"));
        let mut args = vec!["calibrate-network", "-q", "--sensors", s(&sensors)];
        args.extend(["--wand", s(&wand), "--frame", s(&frame)]);
        args.extend(["--observations", s(&points), "--out", s(&rig)]);
        args.extend(["--report", s(&report)]);
        args.extend_from_slice(more);
        psdcal(args)
    };
    fs::create_dir_all(f("out")).unwrap();
    fs::write(f("out/rig.s2.json"), b"mine").unwrap();
    assert_refused(&calibrate(&[]), &f("out/rig.s2.json"), b"mine");
    assert!(!f("out/rig.json").exists() && !f("page").exists());
    fs::remove_file(f("out/rig.s2.json")).unwrap();
    fs::create_dir_all(f("page")).unwrap();
    fs::write(f("page/index.html"), b"mine").unwrap();
    assert_refused(&calibrate(&[]), &f("page/index.html"), b"mine");
    let out = calibrate(&["--force"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = calibrate(&[]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(f("out/rig.s8.json").exists());
}

#[test]
fn calibrate_writes_through_links_keeps_modes_and_refuses_folders() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (t, o) = (valid("template.csv"), valid("observations.csv"));
    let calibrate =
        |out: &Path| psdcal(["calibrate", "-q", "-t", s(&t), "-o", s(&o), "--out", s(out)]);
    // A missing parent folder is created.
    let nested = d.join("out/x.json");
    let run = calibrate(&nested);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(nested.is_file());
    // A link is written through; the target keeps its mode.
    let target = d.join("target.json");
    fs::write(&target, b"old").unwrap();
    fs::set_permissions(&target, fs::Permissions::from_mode(0o600)).unwrap();
    let link = d.join("link.json");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    assert!(calibrate(&link).status.success());
    assert!(fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_ne!(fs::read(&target).unwrap(), b"old");
    let mode = fs::metadata(&target).unwrap().permissions().mode();
    assert_eq!(mode & 0o777, 0o600);
    // A folder is refused clearly.
    let folder = d.join("adir");
    fs::create_dir(&folder).unwrap();
    for out in [folder.clone(), d.join("adir/")] {
        let run = calibrate(&out);
        let err = stderr(&run);
        assert_eq!(run.status.code(), Some(1), "{err}");
        assert!(err.contains("is a folder; give a file name"), "{err}");
    }
}

#[test]
fn a_full_disk_while_writing_the_residuals_leaves_the_calibration_as_it_was() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/example");
    let (t, o) = (
        example.join("template.csv"),
        example.join("observations.csv"),
    );
    let (c, r) = (d.join("c.json"), d.join("r.csv"));
    let args = |c: &Path, r: &Path| {
        vec![
            "calibrate".to_string(),
            "-q".into(),
            "-t".into(),
            s(&t).into(),
            "-o".into(),
            s(&o).into(),
            "--out".into(),
            s(c).into(),
            "--residuals".into(),
            s(r).into(),
        ]
    };
    let first = psdcal(args(&c, &r));
    assert!(first.status.success(), "{}", stderr(&first));
    let (c_len, r_len) = (
        fs::metadata(&c).unwrap().len(),
        fs::metadata(&r).unwrap().len(),
    );
    assert!(
        r_len > c_len + 1024,
        "residuals {r_len} B, calibration {c_len} B"
    );
    fs::write(&c, b"the old calibration").unwrap();
    fs::write(&r, b"the old residuals").unwrap();
    // Files may grow to the calibration's size, not the residuals': the
    // residuals fail with EFBIG (SIGXFSZ ignored) after the calibration
    // was written to its temporary file.
    let limit = format!("--fsize={}", c_len + 512);
    let script = "trap '' XFSZ; exec prlimit \"$@\"";
    let mut command = Command::new("/bin/sh");
    command.args(["-c", script, "sh", &limit, env!("CARGO_BIN_EXE_psdcal")]);
    let out = command.args(args(&c, &r)).output().unwrap();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains(s(&r)) && err.contains("cannot write"), "{err}");
    assert_eq!(fs::read(&c).unwrap(), b"the old calibration");
    assert_eq!(fs::read(&r).unwrap(), b"the old residuals");
    let mut left: Vec<String> = fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["c.json", "r.csv"]);
}

/// The report folders of `diff`, `plan`, `evaluate` (tests/evaluate.rs)
/// and `psd-map` (tests/psd_map.rs) are guarded like the others: a page
/// psdcal did not write is kept, `--force` replaces it, psdcal's own page
/// is replaced freely.
#[test]
fn report_pages_of_diff_and_plan_keep_others_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (t, o) = (valid("template.csv"), valid("observations.csv"));
    let c = d.join("c.json");
    let calibrate = psdcal(["calibrate", "-q", "-t", s(&t), "-o", s(&o), "--out", s(&c)]);
    assert!(calibrate.status.success(), "{}", stderr(&calibrate));
    let diff_dir = d.join("diff");
    fs::create_dir(&diff_dir).unwrap();
    fs::write(diff_dir.join("diff.html"), b"my page").unwrap();
    let diff = |force: bool| {
        let mut args = vec!["-q", "diff", s(&c), s(&c), "--report", s(&diff_dir)];
        args.extend(force.then_some("--force"));
        psdcal(args)
    };
    assert_refused(&diff(false), &diff_dir.join("diff.html"), b"my page");
    assert!(diff(true).status.success());
    assert!(diff(false).status.success(), "{}", stderr(&diff(false)));

    let plan_dir = d.join("plan");
    fs::create_dir(&plan_dir).unwrap();
    fs::write(plan_dir.join("plan_sigma.png"), b"my picture").unwrap();
    let poses = d.join("poses.csv");
    let plan = |force: bool| {
        let mut args = vec![
            "-q",
            "plan",
            "--template",
            s(&t),
            "--snr",
            "40",
            "--f",
            "8",
            "--images",
            "4",
            "--out",
            s(&poses),
            "--report",
            s(&plan_dir),
        ];
        args.extend(force.then_some("--force"));
        psdcal(args)
    };
    assert_refused(
        &plan(false),
        &plan_dir.join("plan_sigma.png"),
        b"my picture",
    );
    assert!(plan(true).status.success());
    assert!(plan(false).status.success());
}
