//! Before any work: the files a command-line command reads and writes
//! (with the `clap` feature), so that no output
//! replaces an input (psdcal-io's `refuse_overwrite`; exit 2).
//!
//! Read off the command's definition, so that every command is covered:
//! each option whose value is a `FILE` (or a positional `NAME.json`) names
//! an input, but `--out`, `--residuals` and `--…-out` (`--poses-out`),
//! which name outputs; `report`'s page (`--out DIR`'s
//! report.html) is an output too, and the calibrations a `--rig` file lists
//! are inputs. Folders (`simulate`, `study`, `--report DIR`) are not
//! checked: nothing is read from them.

use std::path::{Path, PathBuf};

use clap::{ArgMatches, Command};

/// Refuses a command whose output is one of its inputs (or two outputs that
/// are one file); `command` is the definition `matches` were parsed with.
pub fn refuse_input_overwrite(
    command: &Command,
    matches: &ArgMatches,
    limits: psdcal_io::ReadLimits,
) -> Result<(), psdcal_io::IoError> {
    let Some((name, given)) = matches.subcommand() else {
        return Ok(());
    };
    let Some(definition) = command.find_subcommand(name) else {
        return Ok(());
    };
    let mut inputs: Vec<(String, PathBuf)> = Vec::new();
    let mut outputs: Vec<(String, PathBuf)> = Vec::new();
    for arg in definition.get_arguments() {
        let id = arg.get_id().as_str();
        let Some(value_names) = arg.get_value_names() else {
            continue;
        };
        let Ok(Some(values)) = given.try_get_raw(id) else {
            continue;
        };
        // A positional file is named by its value name (`diff`'s `A.json`).
        let option = arg
            .get_long()
            .map_or_else(|| value_names.join(" "), |long| format!("--{long}"));
        let file = value_names
            .iter()
            .any(|n| n == "FILE" || n.ends_with(".json"));
        for path in values.map(PathBuf::from) {
            match (id, file) {
                (id, true) if is_output(id) => outputs.push((option.clone(), path)),
                ("out", false) if name == "report" => {
                    outputs.push((option.clone(), path.join("report.html")));
                }
                (_, true) => {
                    if id == "rig" {
                        inputs.extend(listed_calibrations(&path, limits));
                    }
                    inputs.push((option.clone(), path));
                }
                _ => {}
            }
        }
    }
    psdcal_io::refuse_overwrite(&borrowed(&inputs), &borrowed(&outputs))
}

/// The calibrations a rig file lists (none when it cannot be read: that is
/// the command's own error, reported when it runs).
fn listed_calibrations(rig: &Path, limits: psdcal_io::ReadLimits) -> Vec<(String, PathBuf)> {
    psdcal_io::read_rig_with(rig, limits).map_or_else(
        |_| Vec::new(),
        |file| {
            file.sensors
                .into_iter()
                .map(|s| {
                    (
                        "a calibration listed in --rig".to_string(),
                        s.calibration_path,
                    )
                })
                .collect()
        },
    )
}

fn borrowed(list: &[(String, PathBuf)]) -> Vec<(&str, &Path)> {
    list.iter()
        .map(|(o, p)| (o.as_str(), p.as_path()))
        .collect()
}

/// Whether the option `id` names an output file.
fn is_output(id: &str) -> bool {
    id == "out" || id == "residuals" || id.ends_with("_out")
}
