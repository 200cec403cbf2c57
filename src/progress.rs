//! Progress of parallel work reported on the thread that runs the call: the C ABI promises its
//! progress callbacks that thread (the calling thread when `threads` is 0, otherwise a worker
//! of the call's own pool) and never two calls at once, while the work itself is done by
//! whichever worker is free ([`relay`]).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Sender};
use std::sync::{Mutex, PoisonError};
use std::thread::{self, ThreadId};

use crate::error::{NbhdError, Result};

/// A progress reporter: the fraction done; an error (such as [`NbhdError::Cancelled`]) stops
/// the work.
pub(crate) type Report<'r> = &'r mut (dyn FnMut(f64) -> Result<()> + Send);

/// What the tasks of a [`relay`] tell of their progress.
pub(crate) struct Relay<'r> {
    caller: ThreadId,
    /// The reporter, called directly by the calling thread when it is one of the workers.
    direct: Mutex<Option<Report<'r>>>,
    /// Otherwise the way to the calling thread, which waits for the work and reports.
    /// (`None` ends the work.)
    to_caller: Option<Sender<Option<f64>>>,
    cancelled: AtomicBool,
}

impl Relay<'_> {
    /// Tells that `fraction` of the work is done: reported on the calling thread (directly when
    /// this is it; a worker's own fractions are dropped when the calling thread works too, which
    /// reports at its next tick). Refuses with [`NbhdError::Cancelled`] once the reporter
    /// refused, so that every task stops.
    pub(crate) fn tick(&self, fraction: f64) -> Result<()> {
        if self.cancelled.load(Ordering::Relaxed) {
            return Err(NbhdError::Cancelled);
        }
        if let Some(to) = &self.to_caller {
            // the calling thread may have stopped listening only once the work is over
            let _ = to.send(Some(fraction));
            return Ok(());
        }
        if thread::current().id() != self.caller {
            return Ok(());
        }
        let mut direct = self.direct.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(report) = direct.as_mut() {
            if let Err(e) = report(fraction) {
                self.cancelled.store(true, Ordering::Relaxed);
                return Err(e);
            }
        }
        Ok(())
    }
}

/// Runs `work`, whose tasks may run on any worker, with progress ticks reported by `report` on
/// the calling thread only. On a rayon worker (a call with its own pool, or nested in parallel
/// work) the calling thread takes part in the work and reports its ticks between its own
/// tasks. Elsewhere (`threads` 0 from a thread of the host) the work runs on the pool while
/// the calling thread waits for the ticks and reports them. A refusal of `report` is returned
/// (the work stops at its tasks' next ticks).
pub(crate) fn relay<R: Send>(
    report: Report<'_>,
    work: impl FnOnce(&Relay<'_>) -> Result<R> + Send,
) -> Result<R> {
    let caller = thread::current().id();
    if rayon::current_thread_index().is_some() {
        let relay = Relay {
            caller,
            direct: Mutex::new(Some(report)),
            to_caller: None,
            cancelled: AtomicBool::new(false),
        };
        return work(&relay);
    }
    let (to_caller, ticks) = channel();
    let relay = Relay {
        caller,
        direct: Mutex::new(None),
        to_caller: Some(to_caller),
        cancelled: AtomicBool::new(false),
    };
    let result = Mutex::new(None);
    let mut refused = None;
    rayon::in_place_scope(|scope| {
        let (relay, result) = (&relay, &result);
        scope.spawn(move |_| {
            // sent when the work ends, by a return or a panic
            let _end = End(relay);
            let r = work(relay);
            *result.lock().unwrap_or_else(PoisonError::into_inner) = Some(r);
        });
        // until the work ends
        for fraction in ticks.iter() {
            let Some(fraction) = fraction else { break };
            if refused.is_none() {
                if let Err(e) = report(fraction) {
                    relay.cancelled.store(true, Ordering::Relaxed);
                    refused = Some(e);
                }
            }
        }
    });
    if let Some(e) = refused {
        return Err(e);
    }
    let result = result.into_inner().unwrap_or_else(PoisonError::into_inner);
    result.unwrap_or(Err(NbhdError::Cancelled))
}

/// Tells the calling thread that the work has ended, when dropped.
struct End<'a, 'r>(&'a Relay<'r>);

impl Drop for End<'_, '_> {
    fn drop(&mut self) {
        if let Some(to) = &self.0.to_caller {
            let _ = to.send(None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;
    use std::sync::atomic::AtomicUsize;

    /// Work on two workers whose ticks are reported on the calling thread, from a pool's worker
    /// and from a thread outside any pool; a refusal stops the work with the reporter's error.
    #[test]
    fn ticks_are_reported_on_the_calling_thread_only() {
        let run = |stop_at: Option<usize>| {
            let caller = thread::current().id();
            let (mut calls, mut last) = (0usize, 0.0);
            let tasks = AtomicUsize::new(0);
            let mut report = |f: f64| {
                assert_eq!(thread::current().id(), caller);
                assert!(f >= last);
                (calls, last) = (calls + 1, f);
                match stop_at {
                    Some(s) if calls >= s => Err(NbhdError::Cancelled),
                    _ => Ok(()),
                }
            };
            let r = relay(&mut report, |relay| {
                (0..64).into_par_iter().try_for_each(|_| {
                    std::thread::sleep(std::time::Duration::from_millis(1));
                    let done = tasks.fetch_add(1, Ordering::Relaxed) + 1;
                    relay.tick(done as f64 / 64.0)
                })?;
                Ok(7)
            });
            (r, calls, tasks.into_inner())
        };
        for on_worker in [true, false] {
            let (r, calls, tasks) = if on_worker {
                crate::parallel::with_threads(2, || run(None)).unwrap()
            } else {
                std::thread::spawn(move || run(None)).join().unwrap()
            };
            assert_eq!((r.unwrap(), tasks), (7, 64));
            assert!(calls >= 1, "on a worker: {on_worker}");
            let (r, calls, tasks) = if on_worker {
                crate::parallel::with_threads(2, || run(Some(2))).unwrap()
            } else {
                std::thread::spawn(move || run(Some(2))).join().unwrap()
            };
            assert!(matches!(r, Err(NbhdError::Cancelled)));
            // no report after the refusal
            assert_eq!(calls, 2);
            assert!(tasks <= 64);
        }
    }
}

/// What the run is doing when the progress callback is called.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Neighbourhood search (and the spacing estimate).
    Neighbors,
    /// Normals and curvatures of a step.
    Geometry,
    /// Moving the points.
    Step,
    /// Per-point outputs of the result.
    Outputs,
    /// Finished.
    Done,
}

/// A reporter of progress counted in units out of `total` (steps or iterations, plus one for
/// the rest): it hands `progress` the fraction done, clamped to `[0, 1]`, and turns a `false`
/// into [`NbhdError::Cancelled`].
pub(crate) fn progress_in_units<'a, P: FnMut(f64, Stage) -> bool + ?Sized>(
    total: f64,
    progress: &'a mut P,
) -> impl FnMut(f64, Stage) -> Result<()> + 'a {
    move |f, s| {
        if progress((f / total).clamp(0.0, 1.0), s) {
            Ok(())
        } else {
            Err(NbhdError::Cancelled)
        }
    }
}
