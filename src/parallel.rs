//! Running work on a chosen number of threads: the `threads` option of every parallel call.
//!
//! - `threads = 0` runs on the current rayon pool: rayon's global pool (a thread per core), or
//!   the pool of the worker the call is made from.
//! - `threads = n` (1 ≤ n ≤ [`MAX_THREADS`]) runs on a pool of n worker threads. A larger n is
//!   refused with [`NbhdError::InvalidOption`] before any thread is made.
//!
//! **Pool lifetime.** Making a pool and joining its threads after one small job costs 0.04–0.1
//! ms for one or two threads and 4–10 ms for 4 to 64 threads, against 0.004 ms for a job on a
//! kept pool (rayon 1.12 on the project's loaded 2-core machine), and a few milliseconds are
//! the whole run time of a table of a few thousand points. A new pool's threads also start cold:
//! their memory comes from the system again (7,000 more page faults per call, about 15 ms more
//! of a 270 ms two-thread normals call, when the calls alternated one and two threads). So the
//! [`KEPT_POOLS`] most recently used pools are kept for the next calls, each if it has no more
//! threads than the machine has cores ([`std::thread::available_parallelism`]); every other
//! pool is the call's own and is shut down, its threads joined, before the call returns. At
//! most two kept pools, each of at most a thread per core, so a call with `threads = 2000`
//! leaves no thread behind, and a program that alternates two thread counts (one thread for
//! small clouds, every core for large ones) pays for its pools once.
//!
//! **fork().** A forked child has only the thread that called `fork`: the workers of every
//! pool made before the fork, rayon's global pool included, do not exist in it, and a job sent
//! to them would wait forever. Every call compares the process id with the one nbhd first ran
//! in; in a forked child it never touches a pool made before the fork (neither uses nor frees
//! it) and runs `threads = 0` on a pool of its own with a thread per core instead of rayon's
//! global pool. The kept-pool slot is only ever taken with `try_lock` in a child, so a lock
//! held by a parent's thread at the moment of the fork costs the child its pool cache, never a
//! hang.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, TryLockError};
use std::thread::JoinHandle;

use crate::error::{NbhdError, Result};

/// The largest `threads` value a call accepts. A fixed number rather than a multiple of the
/// machine's cores, so that a call that works on one machine works on another; far above
/// any core count nbhd's work can use (each thread reserves its stack, 2 MiB of address space).
pub const MAX_THREADS: usize = 1024;

/// Checks a `threads` option: 0 ..= [`MAX_THREADS`].
pub fn check_threads(threads: usize) -> Result<()> {
    if threads > MAX_THREADS {
        return Err(NbhdError::InvalidOption {
            name: "threads",
            reason: format!(
                "{threads} is above the maximum of {MAX_THREADS} worker threads \
                 (0 uses a thread per core)"
            ),
        });
    }
    Ok(())
}

/// A pool whose threads nbhd spawned itself, so that they can be joined when it is dropped.
struct Pool {
    /// `None` only while dropping.
    pool: Option<rayon::ThreadPool>,
    threads: usize,
    /// The process the workers were spawned in.
    pid: u32,
    workers: Arc<Mutex<Vec<JoinHandle<()>>>>,
}

impl Pool {
    fn new(threads: usize, pid: u32) -> Result<Self> {
        let workers = Arc::new(Mutex::new(Vec::with_capacity(threads)));
        let handles = Arc::clone(&workers);
        let built = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(move |i| format!("nbhd-{threads}-{i}"))
            .spawn_handler(move |worker| {
                let mut b = std::thread::Builder::new();
                if let Some(name) = worker.name() {
                    b = b.name(name.to_owned());
                }
                if let Some(size) = worker.stack_size() {
                    b = b.stack_size(size);
                }
                let h = b.spawn(move || worker.run())?;
                lock(&handles).push(h);
                Ok(())
            })
            .build();
        match built {
            Ok(pool) => Ok(Self {
                pool: Some(pool),
                threads,
                pid,
                workers,
            }),
            Err(e) => {
                // rayon has already told the threads it did start to exit; wait for them.
                join_all(&workers);
                Err(NbhdError::ThreadPool(format!("{threads} threads: {e}")))
            }
        }
    }

    fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match &self.pool {
            Some(p) => p.install(f),
            None => f(), // unreachable: `pool` is only taken in `drop`
        }
    }
}

impl Drop for Pool {
    fn drop(&mut self) {
        if self.pid != std::process::id() {
            // A pool of the parent process after fork(): its workers do not exist here, and
            // rayon's shutdown would signal them through locks a parent's thread may have
            // held. Leave everything as it is (a leak of one pool's bookkeeping).
            if let Some(p) = self.pool.take() {
                std::mem::forget(p);
            }
            // Keeps the handles from being dropped (detached) without taking their lock.
            std::mem::forget(Arc::clone(&self.workers));
            return;
        }
        // Dropping rayon's pool tells its (idle) workers to exit; then wait until they have.
        drop(self.pool.take());
        join_all(&self.workers);
    }
}

/// Joins the workers, except the calling thread itself should it be one of them (a pool is
/// never dropped on its own worker by this module, but a join there would never return).
fn join_all(workers: &Mutex<Vec<JoinHandle<()>>>) {
    let handles = std::mem::take(&mut *lock(workers));
    let me = std::thread::current().id();
    for h in handles {
        if h.thread().id() != me {
            // A worker that panicked has already unwound; nothing to report here.
            let _ = h.join();
        }
    }
}

/// Locks a mutex whose data stays valid when a holder panicked (entries are replaced whole).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// How many pools are kept for the next calls (see the module documentation).
const KEPT_POOLS: usize = 2;

/// The kept pools, the most recently used first (see the module documentation).
static KEPT: Slot = Mutex::new(Vec::new());

/// The id of the first process that ran a call through this module (0 before the first call).
static FIRST_PID: AtomicU32 = AtomicU32::new(0);

/// The current process id, and whether it is a child forked after nbhd ran in its parent.
fn process() -> (u32, bool) {
    let pid = std::process::id();
    let first = match FIRST_PID.compare_exchange(0, pid, Ordering::AcqRel, Ordering::Acquire) {
        Ok(_) => pid,
        Err(first) => first,
    };
    (pid, first != pid)
}

/// Cores of the machine (1 if unknown).
fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The slot of the kept pools, the most recently used first.
type Slot = Mutex<Vec<Arc<Pool>>>;

/// Takes the kept-pool slot: a plain lock in the process nbhd started in, `try_lock` in a
/// forked child (where a lock held at the fork would never be released).
fn slot(kept: &Slot, forked: bool) -> Option<MutexGuard<'_, Vec<Arc<Pool>>>> {
    if !forked {
        return Some(lock(kept));
    }
    match kept.try_lock() {
        Ok(g) => Some(g),
        Err(TryLockError::Poisoned(e)) => Some(e.into_inner()),
        Err(TryLockError::WouldBlock) => None,
    }
}

/// A pool of `threads` workers: a kept one if one fits, otherwise a new one (kept for the next
/// calls if it has at most a thread per core).
fn pool(threads: usize, pid: u32, forked: bool) -> Result<Arc<Pool>> {
    pool_in(&KEPT, cores(), threads, pid, forked)
}

/// [`pool`] with the slot and the number of cores given.
fn pool_in(kept: &Slot, cores: usize, threads: usize, pid: u32, forked: bool) -> Result<Arc<Pool>> {
    let keep = threads <= cores;
    if keep {
        if let Some(mut g) = slot(kept, forked) {
            if let Some(i) = g.iter().position(|p| p.pid == pid && p.threads == threads) {
                // the most recently used first
                let p = g.remove(i);
                g.insert(0, Arc::clone(&p));
                return Ok(p);
            }
        }
    }
    // Spawned outside the lock: a fork while this runs must not leave the slot locked.
    let p = Arc::new(Pool::new(threads, pid)?);
    if keep {
        // the pools beyond the kept number
        let old = slot(kept, forked).map(|mut g| {
            g.insert(0, Arc::clone(&p));
            let keep = KEPT_POOLS.min(g.len());
            g.split_off(keep)
        });
        // Dropped after the lock is released: the last reference joins its workers. (A
        // parent's pool in a forked child is left alone by `Pool::drop`.)
        drop(old);
    }
    Ok(p)
}

/// Runs `f` with `threads` workers: 0 uses the current rayon pool, n ≥ 1 a pool of n threads
/// (1 runs on a single worker); more than [`MAX_THREADS`] is refused. Results never depend on
/// the choice: every parallel part of nbhd splits work into fixed pieces and joins them in a
/// fixed order. See the module documentation for how long pools live and for fork().
pub fn with_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> Result<R> {
    check_threads(threads)?;
    let (pid, forked) = process();
    if threads == 0 {
        if !forked || rayon::current_thread_index().is_some() {
            // The global pool, or the pool of the worker we are on (which exists in this
            // process, since this code runs on it).
            return Ok(f());
        }
        // rayon's global pool may have been started before the fork: never send it work.
        return Ok(pool(cores(), pid, forked)?.install(f));
    }
    // (The worker check first: current_num_threads would start rayon's global pool.)
    if rayon::current_thread_index().is_some() && rayon::current_num_threads() == threads {
        // Already on a worker of a pool of that size (a nested call): no hop needed.
        return Ok(f());
    }
    Ok(pool(threads, pid, forked)?.install(f))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Threads of this process, from /proc/self/status.
    fn process_threads() -> usize {
        let s = std::fs::read_to_string("/proc/self/status").unwrap();
        let line = s.lines().find(|l| l.starts_with("Threads:")).unwrap();
        line["Threads:".len()..].trim().parse().unwrap()
    }

    #[test]
    fn pools_run_the_requested_number_of_threads() {
        assert_eq!(with_threads(3, rayon::current_num_threads).unwrap(), 3);
        assert_eq!(with_threads(1, rayon::current_num_threads).unwrap(), 1);
        // Nested: a 1-thread call from a 3-thread worker runs on one thread.
        let nested = with_threads(3, || with_threads(1, rayon::current_num_threads).unwrap());
        assert_eq!(nested.unwrap(), 1);
    }

    #[test]
    fn zero_threads_uses_the_current_pool() {
        let outer = with_threads(2, || with_threads(0, rayon::current_num_threads).unwrap());
        assert_eq!(outer.unwrap(), 2);
    }

    #[test]
    fn the_two_most_recent_pools_of_at_most_a_thread_per_core_are_kept() {
        // A slot of this test's own, so that other tests' calls cannot interfere.
        static SLOT: Slot = Mutex::new(Vec::new());
        let pid = std::process::id();
        let kept = || lock(&SLOT).clone();
        let a = pool_in(&SLOT, 4, 2, pid, false).unwrap();
        let b = pool_in(&SLOT, 4, 2, pid, false).unwrap();
        assert!(Arc::ptr_eq(&a, &b), "the kept pool is reused");
        // Above the cores: the call's own pool, and the kept one stays.
        let big = pool_in(&SLOT, 4, 5, pid, false).unwrap();
        assert_eq!(big.threads, 5);
        assert_eq!(kept().len(), 1);
        // Another count within the cores is kept beside it, and calls alternating the two
        // counts reuse both.
        let one = pool_in(&SLOT, 4, 1, pid, false).unwrap();
        for _ in 0..2 {
            assert!(Arc::ptr_eq(&pool_in(&SLOT, 4, 2, pid, false).unwrap(), &a));
            assert!(Arc::ptr_eq(
                &pool_in(&SLOT, 4, 1, pid, false).unwrap(),
                &one
            ));
        }
        // A third count replaces the least recently used (two threads); one stays.
        let c = pool_in(&SLOT, 4, 3, pid, false).unwrap();
        let now = kept();
        assert_eq!(now.len(), 2);
        assert!(Arc::ptr_eq(&now[0], &c) && Arc::ptr_eq(&now[1], &one));
        assert!(!Arc::ptr_eq(&pool_in(&SLOT, 4, 2, pid, false).unwrap(), &a));
        // A pool of another process (as a forked child sees its parent's) is never reused.
        let d = pool_in(&SLOT, 4, 3, pid, true).unwrap();
        assert!(
            Arc::ptr_eq(&c, &d),
            "same process: reused even through try_lock"
        );
        let stale = Arc::new(Pool::new(3, pid).unwrap());
        *lock(&SLOT) = vec![Arc::clone(&stale)];
        // Pretend the stale pool was made by another process: pid + 1 is "us" now.
        let e = pool_in(&SLOT, 4, 3, pid.wrapping_add(1), true).unwrap();
        assert!(!Arc::ptr_eq(&stale, &e));
        assert_eq!(e.install(rayon::current_num_threads), 3);
        // (`e` claims another pid, so dropping it leaks its threads rather than joining them:
        // keep it out of the slot's hands and let it go with the test process.)
        std::mem::forget(e);
        for p in std::mem::take(&mut *lock(&SLOT)) {
            std::mem::forget(p);
        }
    }

    #[test]
    fn dropping_a_pool_joins_its_threads() {
        let p = Pool::new(3, std::process::id()).unwrap();
        let workers = Arc::clone(&p.workers);
        assert_eq!(lock(&workers).len(), 3);
        let ids: Vec<_> = lock(&workers).iter().map(|h| h.thread().id()).collect();
        assert_eq!(ids.len(), 3);
        drop(p);
        // Joined, so the handles are gone (join consumed them).
        assert!(lock(&workers).is_empty());
    }

    #[test]
    fn above_the_maximum_is_refused_without_spawning() {
        let before = process_threads();
        let e = with_threads(MAX_THREADS + 1, || ()).unwrap_err();
        let msg = e.to_string();
        assert!(
            matches!(
                e,
                NbhdError::InvalidOption {
                    name: "threads",
                    ..
                }
            ),
            "{e:?}"
        );
        assert!(msg.contains(&(MAX_THREADS + 1).to_string()), "{msg}");
        assert!(msg.contains("1024"), "{msg}");
        let e = with_threads(100_000, || ()).unwrap_err();
        assert!(e.to_string().contains("100000"), "{e}");
        // Other tests may start threads meanwhile, but not 100,000 of them.
        assert!(process_threads() < before + 64);
        assert!(check_threads(MAX_THREADS).is_ok());
    }
}
