//! `psdcal`: the command-line tool. Argument parsing and output only; the
//! work is done by psdcal-io, psdcal-calib and psdcal-model.
//!
//! Exit codes: 0 success, 1 failure (one `error: ...` line on stderr),
//! 2 usage error (clap).

mod cli;
mod cmd_calibrate;
mod cmd_check;
mod cmd_correct;
mod report;

use std::process::ExitCode;

use clap::Parser;

use crate::cli::{Cli, Job};

fn main() -> ExitCode {
    let (output, job) = match Cli::parse().into_job() {
        Ok(parsed) => parsed,
        Err(usage) => usage.exit(),
    };
    let result = match &job {
        Job::Check(config) => cmd_check::run(config, output),
        Job::Calibrate(config) => cmd_calibrate::run(config, output),
        Job::Correct(config) => cmd_correct::run(config, output),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            report::print_error(&error);
            ExitCode::FAILURE
        }
    }
}
