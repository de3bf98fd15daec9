//! The psdcal command-line tool's library: argument parsing and output
//! only; the work is done by the `psdcal` library. `src/main.rs` is the
//! `psdcal` binary.
//!
//! Exit codes: 0 success, 1 failure (one `error: ...` line on stderr),
//! 2 usage error (clap, or an output that is one of the inputs), 141
//! (128 + SIGPIPE, as a shell shows a process a closed pipe ended) with
//! nothing printed when standard output was closed by its reader.

pub mod args;
pub mod choice;
pub mod cli;
pub mod cli_locate;
pub mod cli_sim;
mod cmd_aoa;
mod cmd_calibrate;
pub mod cmd_calibrate_in_situ;
mod cmd_check;
mod cmd_correct;
mod cmd_demo;
pub mod cmd_demodulate;
pub mod cmd_diff;
pub mod cmd_evaluate;
pub mod cmd_export;
pub mod cmd_focal_check;
pub mod cmd_gains;
mod cmd_locate;
mod cmd_map;
pub mod cmd_network;
pub mod cmd_plan;
pub mod cmd_psd_map;
pub mod cmd_report;
mod cmd_simulate;
pub mod cmd_simulate_positioning;
pub mod cmd_simulate_scan;
mod cmd_study;
pub mod cmd_track;
mod guard;
pub mod messages;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches};

use crate::cli::{Cli, Job};

/// Parses the arguments, runs the job and prints; the process's exit code.
pub fn main() -> ExitCode {
    // Parsed in its own scope: the job reuses clap's ~150 KB once it is freed.
    let (output, job, limits, force) = {
        let mut command = Cli::command();
        let matches = command.get_matches_mut();
        let cli = match Cli::from_arg_matches(&matches) {
            Ok(cli) => cli,
            Err(usage) => usage.exit(),
        };
        let (limits, force) = (cli.read_limits(), cli.force);
        let (output, job) = match cli.into_job() {
            Ok(parsed) => parsed,
            Err(usage) => usage.format(&mut Cli::command()).exit(),
        };
        if let Err(clash) = guard::check(&command, &matches, limits) {
            eprintln!("error: {clash}");
            return ExitCode::from(2);
        }
        (output, job, limits, force)
    };
    let result = match &job {
        Job::Check(files, load) => cmd_check::run(files, load, output),
        Job::Calibrate(config) => cmd_calibrate::run(config, output),
        Job::Gains(args) => cmd_gains::run(args, output, limits),
        Job::PsdMap(args) => cmd_psd_map::run(args, output, limits),
        Job::SimulateScan(args) => cmd_simulate_scan::run(args, output),
        Job::Simulate(args) => cmd_simulate::run(args, output, limits, force),
        Job::Study(config) => cmd_study::run(config, output),
        Job::Demo(args) => cmd_demo::run(args, output),
        Job::Demodulate(args) => cmd_demodulate::run(args, output, limits),
        Job::Track(args) => cmd_track::run(args, output, limits),
        Job::Plan(args) => cmd_plan::run(args, output, limits),
        Job::FocalCheck(args) => cmd_focal_check::run(args, output, limits),
        Job::CalibrateInSitu(args) => cmd_calibrate_in_situ::run(args, output, limits),
        Job::CalibrateNetwork(args) => cmd_network::run(args, output, limits, force),
        Job::SimulateNetwork(args) => cmd_network::simulate(args, output, force),
        Job::Correct(config) => cmd_correct::run(config, output, limits),
        Job::Aoa(config) => cmd_aoa::run(config, output, limits),
        Job::Locate(config) => cmd_locate::run(config, output, limits),
        Job::Map(request, out) => cmd_map::run(request, out.as_deref(), output),
        Job::Report(config) => cmd_report::run(config, output, limits, force),
        Job::Evaluate(args) => cmd_evaluate::run(args, output, limits),
        Job::SimulatePositioning(args) => cmd_simulate_positioning::run(args, output, force),
        Job::Export(args) => cmd_export::run(args, output, limits),
        Job::Diff(args) => cmd_diff::run(args, output, limits),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) if psdcal::is_closed_output(&*error) => ExitCode::from(141),
        Err(error) => {
            messages::print_error(&messages::lower(error));
            ExitCode::FAILURE
        }
    }
}
