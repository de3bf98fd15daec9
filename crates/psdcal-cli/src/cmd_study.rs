//! `psdcal study`: the paper's Monte Carlo evaluation from one command.
//!
//! The library checks everything before the work starts and writes the
//! files; here the trials get a progress bar (on a terminal only) and
//! Ctrl-C stops the study before anything is written.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use psdcal::StudyRequest;

use crate::messages::Output;

/// Runs `study`.
pub fn run(config: &StudyRequest, output: Output) -> anyhow::Result<()> {
    let plan = psdcal::plan_study(config)?;
    let bar = progress_bar(plan.trial_count(), output);
    let cancel = Arc::new(AtomicBool::new(false));
    {
        let cancel = cancel.clone();
        // A second handler cannot be installed; without one, Ctrl-C just ends the process
        // before anything is written, which is also safe.
        let _ = ctrlc::set_handler(move || cancel.store(true, Ordering::SeqCst));
    }
    let tick = || bar.inc(1);
    let outcome = plan.run(&tick, &cancel);
    bar.finish_and_clear();
    let outcome = outcome?;
    crate::messages::emit(output, &outcome.summary(&config.out))
}

fn progress_bar(total: u64, output: Output) -> ProgressBar {
    if output != Output::Text || !std::io::stderr().is_terminal() {
        return ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
    }
    let bar = ProgressBar::new(total);
    if let Ok(style) =
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} trials, {eta} left")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
