//! A second thread for the work that follows the fit.
//!
//! What the finished fit is asked (covariance and linearity check,
//! residual-structure tests, valid region, statistics) is a few independent
//! jobs. The caller posts them, then works through them itself from the
//! last one posted while a second thread takes them from the first: the
//! two meet wherever the work divides, whichever thread is faster, and a
//! job that neither has taken when the caller gets to it runs on the
//! caller. The second thread is started with the calibration, not when its
//! work is ready: a new thread takes 0.1–1 ms to run on a small virtual
//! machine (measured here), which then overlaps the initialisation. It is
//! detached: the caller never waits for it to start or to wind down, only
//! for a job it has taken.
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

/// The posted jobs, in order.
type Queue = Arc<Mutex<Vec<Slot>>>;

fn take(slot: &Slot) -> Option<Job> {
    slot.lock().unwrap_or_else(|e| e.into_inner()).take()
}

/// The first posted job nobody has taken.
fn take_first(queue: &Queue) -> Option<Job> {
    let slots = queue.lock().unwrap_or_else(|e| e.into_inner()).clone();
    slots.iter().find_map(take)
}

/// A started second thread waiting for jobs (or none: inside a rayon
/// worker, or when the thread could not be started).
pub(crate) struct Helper {
    queue: Queue,
    wake: Option<Sender<()>>,
}

impl Helper {
    /// Starts the thread (none inside a rayon worker). Once woken it runs
    /// the posted jobs nobody has taken, first to last, and ends.
    pub(crate) fn spawn() -> Self {
        let queue: Queue = Arc::new(Mutex::new(Vec::new()));
        if rayon::current_thread_index().is_some() {
            return Self { queue, wake: None };
        }
        let (wake, woken) = channel::<()>();
        let theirs = queue.clone();
        let elsewhere = other_cores();
        let started = Builder::new()
            .name("psdcal-fit-helper".into())
            .spawn(move || {
                elsewhere();
                if woken.recv().is_ok() {
                    while let Some(job) = take_first(&theirs) {
                        job();
                    }
                }
            });
        Self {
            queue,
            wake: started.ok().map(|_| wake),
        }
    }

    /// Posts `f` and wakes the second thread (the first time);
    /// [`Pending::wait`] runs `f` on the caller's thread when nobody has
    /// taken it by then.
    pub(crate) fn run<R: Send + 'static>(
        &mut self,
        f: impl FnOnce() -> R + Send + 'static,
    ) -> Pending<R> {
        let (send, receive) = channel();
        let job: Job = Box::new(move || {
            // The waiting thread re-raises a panic (Pending::wait).
            let _ = send.send(catch_unwind(AssertUnwindSafe(f)));
        });
        let slot: Slot = Arc::new(Mutex::new(Some(job)));
        self.queue
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(slot.clone());
        if let Some(wake) = self.wake.take() {
            // A thread that is gone leaves the jobs to the caller.
            let _ = wake.send(());
        }
        Pending {
            slot,
            result: receive,
        }
    }
}

/// Keeps the calling thread off the core the caller is on now (Linux; a
/// no-op elsewhere, on one core, or when the system refuses): a thread
/// started or woken by a busy thread tends to be queued on that thread's
/// core and to wait there until it is preempted (measured here: a helper
/// woken 0.03–1.6 ms late, often only once the caller had finished).
#[cfg(target_os = "linux")]
fn other_cores() -> impl FnOnce() + Send {
    use rustix::thread::{sched_getaffinity, sched_getcpu, sched_setaffinity};
    let here = sched_getcpu();
    let allowed = sched_getaffinity(None).ok();
    move || {
        let Some(mut set) = allowed else {
            return;
        };
        if set.count() > 1 && set.is_set(here) {
            set.unset(here);
            let _ = sched_setaffinity(None, &set);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn other_cores() -> impl FnOnce() + Send {
    || {}
}

/// The result of a job given to [`Helper::run`].
pub(crate) struct Pending<R> {
    slot: Slot,
    result: Receiver<std::thread::Result<R>>,
}

impl<R> Pending<R> {
    /// The result: the job runs here when nobody has taken it; otherwise
    /// the wait spins for up to [`SPIN`] before it blocks (a blocked thread
    /// of a small virtual machine wakes up late: 0.18 ms measured here). A
    /// panic of the job continues on this thread.
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
    fn the_helper_takes_jobs_from_the_first_the_caller_from_the_last() {
        let caller = std::thread::current().id();
        let mut helper = Helper::spawn();
        let jobs: Vec<_> = (0..3)
            .map(|_| helper.run(move || std::thread::current().id()))
            .collect();
        // Given time, the thread runs every posted job, first to last.
        std::thread::sleep(Duration::from_millis(200));
        for job in jobs {
            assert_ne!(job.wait(), caller);
        }
        // Woken once: a job posted after it ended runs on the caller.
        let late = helper.run(move || std::thread::current().id());
        assert_eq!(late.wait(), caller);
    }

    #[test]
    fn every_job_runs_once_whoever_takes_it() {
        for _ in 0..50 {
            let mut helper = Helper::spawn();
            let jobs: Vec<_> = (0..6u64).map(|k| helper.run(move || k * k)).collect();
            let got: Vec<u64> = jobs.into_iter().rev().map(Pending::wait).collect();
            assert_eq!(got, [25, 16, 9, 4, 1, 0]);
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

    #[cfg(target_os = "linux")]
    #[test]
    fn the_helper_keeps_off_one_core() {
        use rustix::thread::{sched_getaffinity, sched_getcpu};
        let allowed = sched_getaffinity(None).expect("an affinity");
        let pin = other_cores();
        let (got, on) = std::thread::spawn(move || {
            pin();
            (
                sched_getaffinity(None).expect("an affinity"),
                sched_getcpu(),
            )
        })
        .join()
        .expect("the thread runs");
        let expected = if allowed.count() > 1 {
            allowed.count() - 1
        } else {
            allowed.count()
        };
        assert_eq!(got.count(), expected);
        assert!(got.is_set(on), "it runs where it is allowed to");
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
