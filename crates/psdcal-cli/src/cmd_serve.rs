//! `psdcal serve`: a rig's positions live over HTTP — a 3-D page, the
//! Server-Sent Events of `/stream` and `/rig` (the work is `psdcal::serve`).

use clap::Args;

use crate::messages::Output;

/// A rig's positions live in the browser: a 3-D page, /stream (Server-Sent Events) and /rig
#[derive(Debug, Clone, PartialEq, Args)]
pub struct ServeArgs {
    #[command(flatten)]
    pub track: crate::cmd_track::TrackArgs,
    /// Replay the --raw recording at its sample rate (from the first viewer on)
    #[arg(long)]
    pub realtime: bool,
    /// Address to listen on (another than 127.0.0.1 opens the view to the network)
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1")]
    pub bind: String,
    /// Port (0: any free port)
    #[arg(long, value_name = "P", default_value_t = 8080)]
    pub port: u16,
}

/// Runs `serve` until the input ends.
pub fn run(args: &ServeArgs, output: Output, limits: psdcal::ReadLimits) -> anyhow::Result<()> {
    let request = psdcal::ServeRequest {
        track: crate::cmd_track::request(&args.track, limits)?,
        realtime: args.realtime,
        bind: format!("{}:{}", args.bind, args.port),
    };
    let summary = psdcal::serve(&request, std::io::stdin().lock(), |address| {
        eprintln!("listening on http://{address}/");
    })?;
    if output != Output::Quiet {
        eprintln!(
            "serve: {} samples, {} windows",
            summary.samples, summary.windows
        );
    }
    Ok(())
}
