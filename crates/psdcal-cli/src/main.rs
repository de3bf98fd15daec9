//! `psdcal`: the command-line tool (psdcal-cli's library does the work).
//!
//! Exit codes: 0 success, 1 failure (one `error: ...` line on stderr),
//! 2 usage error (clap), 141 when standard output was closed (`| head`).

fn main() -> std::process::ExitCode {
    psdcal_cli::main()
}
