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
pub mod cmd_serve;
mod cmd_simulate;
pub mod cmd_simulate_positioning;
pub mod cmd_simulate_scan;
mod cmd_study;
pub mod cmd_track;
pub mod messages;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches};

use crate::cli::Command::*;
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
        if let Err(clash) = psdcal::refuse_input_overwrite(&command, &matches, limits) {
            messages::say(&format!("error: {clash}\n"));
            return ExitCode::from(2);
        }
        (output, job, limits, force)
    };
    let result = match &job {
        Job::Check(files, load) => cmd_check::run(files, load, output),
        Job::Calibrate(config) => cmd_calibrate::run(config, output),
        Job::Plain(Gains(args)) => cmd_gains::run(args, output, limits),
        Job::Plain(PsdMap(args)) => cmd_psd_map::run(args, output, limits, force),
        Job::Plain(SimulateScan(args)) => cmd_simulate_scan::run(args, output),
        Job::Plain(Simulate(args)) => cmd_simulate::run(args, output, limits, force),
        Job::Study(config) => cmd_study::run(config, output),
        Job::Plain(Demo(args)) => cmd_demo::run(args, output),
        Job::Plain(Demodulate(args)) => cmd_demodulate::run(args, output, limits),
        Job::Plain(Track(args)) => cmd_track::run(args, output, limits),
        Job::Plain(Serve(args)) => cmd_serve::run(args, output, limits),
        Job::Plain(Plan(args)) => cmd_plan::run(args, output, limits, force),
        Job::Plain(FocalCheck(args)) => cmd_focal_check::run(args, output, limits),
        Job::Plain(CalibrateInSitu(args)) => cmd_calibrate_in_situ::run(args, output, limits),
        Job::Plain(CalibrateNetwork(args)) => cmd_network::run(args, output, limits, force),
        Job::Plain(SimulateNetwork(args)) => cmd_network::simulate(args, output, force),
        Job::Correct(config) => cmd_correct::run(config, output, limits),
        Job::Aoa(config) => cmd_aoa::run(config, output, limits),
        Job::Locate(config) => cmd_locate::run(config, output, limits),
        Job::Map(request, out) => cmd_map::run(request, out.as_deref(), output),
        Job::Plain(Report(config)) => cmd_report::run(config, output, limits, force),
        Job::Plain(Evaluate(args)) => cmd_evaluate::run(args, output, limits, force),
        Job::Plain(SimulatePositioning(args)) => cmd_simulate_positioning::run(args, output, force),
        Job::Plain(Export(args)) => cmd_export::run(args, output, limits),
        Job::Plain(Diff(args)) => cmd_diff::run(args, output, limits, force),
        // Commands with their own job were turned into it by `into_job`.
        Job::Plain(_) => unreachable!("every command's job is dispatched above"),
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
