//! The malformed-input suite: every file in `tests/data/malformed/` is fed to
//! the `psdcal` binary, which must fail cleanly: exit code 1, one `error:`
//! line naming the file and the expected line, what was wrong, and no panic
//! and no NaN anywhere in its output.

mod common;

use std::collections::BTreeSet;
use std::path::PathBuf;

use common::{data_dir, psdcal, stderr, stdout, valid};

/// How a malformed file is fed to psdcal.
#[derive(Debug, Clone, Copy)]
enum Role {
    /// `check --template <valid> --observations FILE`
    Observations,
    /// `check --template <valid> --observations FILE --strict`
    ObservationsStrict,
    /// `check --template <valid> --signals FILE`
    Signals,
    /// `check --template FILE --observations <valid>`
    Template,
    /// `correct --calibration FILE --points <valid>`
    Calibration,
    /// `correct --calibration <valid> --points FILE`
    Points,
}

/// One malformed file, how it is used, the line the error must name (`None`
/// when the file has no line to name) and a fragment of the expected message.
struct Case {
    file: &'static str,
    role: Role,
    line: Option<usize>,
    says: &'static str,
}

const fn case(file: &'static str, role: Role, line: Option<usize>, says: &'static str) -> Case {
    Case {
        file,
        role,
        line,
        says,
    }
}

#[rustfmt::skip]
const CASES: &[Case] = &[
    // observations.csv
    case("obs_missing_column.csv", Role::Observations, Some(3), "missing column 'y_mm'"),
    case("obs_bad_number.csv", Role::Observations, Some(5), "column 'x_mm' (3): expected a number, found 'abc'"),
    case("obs_nan.csv", Role::Observations, Some(4), "column 'y_mm' (4): expected a finite number, found a not-a-number value"),
    case("obs_inf.csv", Role::Observations, Some(2), "column 'x_mm' (3): expected a finite number, found an infinite value 'inf'"),
    case("obs_huge_value.csv", Role::Observations, Some(5), "found '1e400', which is beyond the range of 64-bit floating point"),
    case("obs_unknown_led.csv", Role::Observations, Some(5), "LED '99' is not in the template"),
    case("obs_duplicate_row.csv", Role::Observations, Some(7), "image '1', LED '2' appears twice (first on line 3)"),
    case("obs_empty.csv", Role::Observations, None, "the file is empty; expected a header row"),
    case("obs_header_only.csv", Role::Observations, Some(2), "the file has a header but no data rows"),
    // Read line by line: the first bad byte in file order (PNG's 0x89) is named.
    case("obs_binary.csv", Role::Observations, Some(3), "byte 0x89 at byte offset 28 is not UTF-8"),
    case("obs_semicolon.csv", Role::Observations, Some(1), "the header is separated by semicolons (;)"),
    case("obs_tab.csv", Role::Observations, Some(2), "the header is separated by tabs"),
    case("obs_too_few_fields.csv", Role::Observations, Some(3), "expected 4 fields as in the header on line 1, found 3"),
    case("obs_too_many_fields.csv", Role::Observations, Some(3), "expected 4 fields as in the header on line 1, found 5"),
    case("obs_crlf_bad_value.csv", Role::Observations, Some(4), "column 'y_mm' (4): expected a number, found '--1'"),
    case("obs_unterminated_quote.csv", Role::Observations, Some(3), "opens a quote that is not closed"),
    case("obs_not_utf8.csv", Role::Observations, Some(3), "byte 0xe9 at byte offset 36 is not UTF-8"),
    case("obs_empty_led.csv", Role::Observations, Some(3), "column 'led' (2): expected an LED identifier, found an empty field"),
    case("obs_three_points_strict.csv", Role::ObservationsStrict, Some(15), "image 'd' has 3 points on the sensor; expected at least 4"),
    // signals.csv
    case("signals_zero_total.csv", Role::Signals, Some(4), "electrode amplitudes sum to 0 (must be positive)"),
    case("signals_negative_total.csv", Role::Signals, Some(3), "electrode amplitudes sum to -1.25 (must be positive)"),
    case("signals_nan.csv", Role::Signals, Some(3), "column 'vx2' (4): expected a finite number"),
    // template.csv
    case("template_duplicate_led.csv", Role::Template, Some(7), "LED '2' appears twice (first on line 3)"),
    case("template_nonfinite.csv", Role::Template, Some(3), "column 'X_mm' (2): expected a finite number, found an infinite value '-inf'"),
    case("template_missing_column.csv", Role::Template, Some(2), "missing column 'Y_mm'"),
    case("template_bad_number.csv", Role::Template, Some(5), "column 'Y_mm' (3): expected a number, found '1OO'"),
    // points.csv
    case("points_bad_number.csv", Role::Points, Some(3), "column 'y_mm' (3): expected a number, found 'x'"),
    case("points_missing_column.csv", Role::Points, Some(2), "missing column 'x_mm'"),
    // calibration.json
    case("cal_wrong_format.json", Role::Calibration, Some(2), "\"format\" is \"camera-calibration\"; expected \"psdcal-calibration\""),
    case("cal_future_version.json", Role::Calibration, Some(3), "format version 3 was written by a newer psdcal"),
    case("cal_negative_f.json", Role::Calibration, Some(13), "expected a positive number of mm, found -1"),
    case("cal_truncated.json", Role::Calibration, Some(102), "EOF while parsing"),
    case("cal_asymmetric_covariance.json", Role::Calibration, Some(101), "covariance.matrix is not symmetric"),
    case("cal_unknown_parameter.json", Role::Calibration, Some(30), "unknown variant `cz`"),
    case("cal_nan.json", Role::Calibration, Some(20), "expected value"),
    case("cal_not_json.json", Role::Calibration, Some(1), "expected ident"),
];

fn malformed(name: &str) -> PathBuf {
    data_dir("malformed").join(name)
}

fn args(case: &Case) -> Vec<std::ffi::OsString> {
    let file = malformed(case.file).into_os_string();
    let mut args: Vec<std::ffi::OsString> = match case.role {
        Role::Observations | Role::ObservationsStrict => vec![
            "check".into(),
            "--template".into(),
            valid("template.csv").into(),
            "--observations".into(),
            file,
        ],
        Role::Signals => vec![
            "check".into(),
            "--template".into(),
            valid("template.csv").into(),
            "--signals".into(),
            file,
        ],
        Role::Template => vec![
            "check".into(),
            "--template".into(),
            file,
            "--observations".into(),
            valid("observations.csv").into(),
        ],
        Role::Calibration => vec![
            "correct".into(),
            "--calibration".into(),
            file,
            "--points".into(),
            valid("points.csv").into(),
        ],
        Role::Points => vec![
            "correct".into(),
            "--calibration".into(),
            valid("calibration.json").into(),
            "--points".into(),
            file,
        ],
    };
    if let Role::ObservationsStrict = case.role {
        args.push("--strict".into());
    }
    args
}

#[test]
fn every_malformed_file_fails_cleanly_on_its_line() {
    assert!(CASES.len() >= 20);
    let mut failures = Vec::new();
    for case in CASES {
        let out = psdcal(args(case));
        let err = stderr(&out);
        let mut problems = Vec::new();
        if out.status.code() != Some(1) {
            problems.push(format!("exit code {:?}, expected 1", out.status.code()));
        }
        let path = malformed(case.file).display().to_string();
        if let Some(line) = case.line {
            let at = format!("error: {path}:{line}:");
            if !err.contains(&at) {
                problems.push(format!("stderr does not contain {at:?}"));
            }
        } else if !err.contains(&format!("error: {path}: ")) {
            problems.push("stderr does not name the file".to_string());
        }
        if !err.contains(case.file) {
            problems.push("stderr does not name the file".to_string());
        }
        if !err.contains(case.says) {
            problems.push(format!("stderr does not say {:?}", case.says));
        }
        let error_lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error: ")).collect();
        if error_lines.len() != 1 || !err.ends_with('\n') || err.lines().count() != 1 {
            problems.push("stderr is not exactly one 'error:' line".to_string());
        }
        if !error_lines.first().is_some_and(|l| l.contains("; ")) {
            problems.push("the error line has no '; <what to do>' part".to_string());
        }
        if err.contains("panicked") || err.contains("RUST_BACKTRACE") {
            problems.push("psdcal panicked".to_string());
        }
        if err.contains("NaN") || stdout(&out).contains("NaN") {
            problems.push("NaN in the output".to_string());
        }
        if !out.stdout.is_empty() {
            problems.push(format!("stdout is not empty: {:?}", stdout(&out)));
        }
        if !problems.is_empty() {
            failures.push(format!(
                "{}: {}\n    stderr: {err}",
                case.file,
                problems.join("; ")
            ));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

#[test]
fn every_file_in_the_malformed_folder_is_in_the_table() {
    let on_disk: BTreeSet<String> = std::fs::read_dir(data_dir("malformed"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    let in_table: BTreeSet<String> = CASES.iter().map(|c| c.file.to_string()).collect();
    assert_eq!(on_disk, in_table);
    assert_eq!(in_table.len(), CASES.len(), "a file is listed twice");
}

#[test]
fn the_short_image_is_only_a_warning_without_strict() {
    let file = malformed("obs_three_points_strict.csv");
    let out = psdcal([
        "--quiet".as_ref(),
        "check".as_ref(),
        "--template".as_ref(),
        valid("template.csv").as_os_str(),
        "--observations".as_ref(),
        file.as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(
        stderr(&out),
        format!(
            "warning: {}:15: image 'd' has 3 points on the sensor; expected at least 4: image \
             dropped\n",
            file.display()
        )
    );
}

#[test]
fn a_missing_file_fails_cleanly() {
    let out = psdcal([
        "check".as_ref(),
        "--template".as_ref(),
        valid("template.csv").as_os_str(),
        "--observations".as_ref(),
        malformed("no_such_file.csv").as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(err.starts_with("error: "), "{err}");
    assert!(
        err.contains("no_such_file.csv: cannot read the file: "),
        "{err}"
    );
    assert!(err
        .trim_end()
        .ends_with("; check the path and that the file is readable"));
}
