//! `psdcal demo`: the main job on built-in data (the library's `demo`),
//! printed.

use crate::cli_sim::DemoArgs;
use crate::messages::Output;

/// Runs `demo`.
pub fn run(args: &DemoArgs, output: Output) -> anyhow::Result<()> {
    crate::messages::emit(output, &psdcal::demo(args.seed)?.summary())
}
