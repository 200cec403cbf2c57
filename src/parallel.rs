//! Running work on a chosen number of threads.

use std::sync::{Arc, Mutex};

use crate::error::{NbhdError, Result};

/// Pools made so far, one per thread count. A pool's threads are spawned once and kept, as
/// rayon keeps its global pool: spawning a pool per call costs a millisecond or more, which
/// is the whole run time of a table of a few thousand points.
static POOLS: Mutex<Vec<(usize, Arc<rayon::ThreadPool>)>> = Mutex::new(Vec::new());

/// The pool of `threads` workers, made on first use.
fn pool(threads: usize) -> Result<Arc<rayon::ThreadPool>> {
    // A poisoned lock only means another thread panicked while holding it; the list itself
    // is always valid (entries are pushed whole).
    let mut pools = POOLS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, p)) = pools.iter().find(|(t, _)| *t == threads) {
        return Ok(Arc::clone(p));
    }
    let p = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(move |i| format!("nbhd-{threads}-{i}"))
            .build()
            .map_err(|e| NbhdError::ThreadPool(e.to_string()))?,
    );
    pools.push((threads, Arc::clone(&p)));
    Ok(p)
}

/// Runs `f` with `threads` workers: 0 uses the current rayon pool, n ≥ 1 a pool of n threads
/// (1 runs on a single worker). Results never depend on the choice: every parallel part of
/// nbhd splits work into fixed pieces and joins them in a fixed order.
pub fn with_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> Result<R> {
    if threads == 0 {
        return Ok(f());
    }
    if rayon::current_num_threads() == threads && rayon::current_thread_index().is_some() {
        // Already on a worker of a pool of that size (a nested call): no hop needed.
        return Ok(f());
    }
    Ok(pool(threads)?.install(f))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pools_are_made_once_per_thread_count() {
        let a = pool(3).unwrap();
        let b = pool(3).unwrap();
        assert!(Arc::ptr_eq(&a, &b));
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
}
