//! Running work on a chosen number of threads.

use crate::error::{NbhdError, Result};

/// Runs `f` with `threads` workers: 0 uses the current rayon pool, n ≥ 1 a pool of n threads
/// (1 runs on a single worker). Results never depend on the choice: every parallel part of
/// nbhd splits work into fixed pieces and joins them in a fixed order.
pub fn with_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> Result<R> {
    if threads == 0 {
        return Ok(f());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| NbhdError::ThreadPool(e.to_string()))?;
    Ok(pool.install(f))
}
