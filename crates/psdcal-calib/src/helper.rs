//! A second thread for the work that follows the fit.
//!
//! What the finished fit is asked (covariance and linearity check on one
//! side; residual-structure tests, valid region and statistics on the
//! other) can run on two threads. The second one is started with the
//! calibration, not when its work is ready: a new thread takes 0.1–1 ms to
//! run on a small virtual machine (measured here), which then overlaps the
//! initialisation. It is detached: the caller hands it a job and never
//! waits for it to start or to wind down. If it has not taken the job by
//! the time the caller has done its own share, the caller runs the job
//! itself, so a late thread costs a clone, not a wait.
//!
//! Inside a rayon worker (a study's parallel fits) every core is busy
//! already, and no thread is started. The rayon pool itself is not used:
//! its idle workers spin, which on a small fit costs more than the second
//! core gains. Results do not depend on which thread computes what.

use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::mpsc::{channel, Receiver, Sender, TryRecvError};
use std::sync::{Arc, Mutex};
use std::thread::Builder;
use std::time::{Duration, Instant};

/// Longest a wait for the other thread's result spins before it blocks.
pub(crate) const SPIN: Duration = Duration::from_micros(500);

/// A job for the second thread.
type Job = Box<dyn FnOnce() + Send>;

/// Where a job waits for whichever thread takes it first.
type Slot = Arc<Mutex<Option<Job>>>;

fn take(slot: &Slot) -> Option<Job> {
    slot.lock().unwrap_or_else(|e| e.into_inner()).take()
}

/// A started second thread waiting for its one job (or none: inside a
/// rayon worker, or when the thread could not be started).
pub(crate) struct Helper {
    slot: Slot,
    wake: Option<Sender<()>>,
}

impl Helper {
    /// Starts the thread (none inside a rayon worker).
    pub(crate) fn spawn() -> Self {
        let slot: Slot = Arc::new(Mutex::new(None));
        if rayon::current_thread_index().is_some() {
            return Self { slot, wake: None };
        }
        let (wake, woken) = channel::<()>();
        let theirs = slot.clone();
        let started = Builder::new()
            .name("psdcal-fit-helper".into())
            .spawn(move || {
                if woken.recv().is_ok() {
                    if let Some(job) = take(&theirs) {
                        job();
                    }
                }
            });
        Self {
            slot,
            wake: started.ok().map(|_| wake),
        }
    }

    /// Hands `f` to the second thread; [`Pending::wait`] runs it on the
    /// caller's thread when that thread has not taken it (or there is none,
    /// or it has had its job).
    pub(crate) fn run<R: Send + 'static>(
        &mut self,
        f: impl FnOnce() -> R + Send + 'static,
    ) -> Pending<R> {
        let (send, receive) = channel();
        let job: Job = Box::new(move || {
            // The waiting thread re-raises a panic (Pending::wait).
            let _ = send.send(catch_unwind(AssertUnwindSafe(f)));
        });
        *self.slot.lock().unwrap_or_else(|e| e.into_inner()) = Some(job);
        if let Some(wake) = self.wake.take() {
            // A thread that is gone leaves the job to the caller.
            let _ = wake.send(());
        }
        Pending {
            slot: self.slot.clone(),
            result: receive,
        }
    }
}

/// The result of a job given to [`Helper::run`].
pub(crate) struct Pending<R> {
    slot: Slot,
    result: Receiver<std::thread::Result<R>>,
}

impl<R> Pending<R> {
    /// The result: the job runs here when the second thread has not taken
    /// it; otherwise the wait spins for up to [`SPIN`] before it blocks (a
    /// blocked thread of a small virtual machine wakes up late: 0.18 ms
    /// measured here). A panic of the job continues on this thread.
    pub(crate) fn wait(self) -> R {
        if let Some(job) = take(&self.slot) {
            job();
        }
        let start = Instant::now();
        let mut spins = 0u32;
        let received = loop {
            match self.result.try_recv() {
                Ok(result) => break Ok(result),
                Err(TryRecvError::Disconnected) => break Err(()),
                Err(TryRecvError::Empty) => {
                    spins = spins.wrapping_add(1);
                    if spins.is_multiple_of(64) && start.elapsed() > SPIN {
                        break self.result.recv().map_err(|_| ());
                    }
                    std::hint::spin_loop();
                }
            }
        };
        match received {
            Ok(Ok(r)) => r,
            Ok(Err(panic)) => resume_unwind(panic),
            // The job sends before it ends, and whoever takes it runs it:
            // the channel cannot close without a result.
            Err(_) => resume_unwind(Box::new("the fit's helper thread ended without a result")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jobs_run_once_on_the_helper_then_inline() {
        let caller = std::thread::current().id();
        {
            let mut helper = Helper::spawn();
            let first = helper.run(move || std::thread::current().id());
            // Given time to start, the thread takes the first job.
            std::thread::sleep(Duration::from_millis(200));
            assert_ne!(first.wait(), caller, "the first job runs on the helper");
            let second = helper.run(move || std::thread::current().id());
            assert_eq!(second.wait(), caller, "a second job runs on the caller");
        }
    }

    #[test]
    fn inside_a_rayon_worker_jobs_run_on_the_caller() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a pool");
        pool.install(|| {
            let caller = std::thread::current().id();
            let mut helper = Helper::spawn();
            assert!(helper.wake.is_none(), "no thread is started");
            let job = helper.run(move || std::thread::current().id());
            assert_eq!(job.wait(), caller);
        });
    }

    #[test]
    fn a_panicking_job_panics_the_caller() {
        let outcome = catch_unwind(|| {
            let mut helper = Helper::spawn();
            helper.run(|| -> u8 { panic!("job failed") }).wait()
        });
        let payload = outcome.expect_err("the panic reaches the caller");
        assert_eq!(payload.downcast_ref::<&str>(), Some(&"job failed"));
    }
}
