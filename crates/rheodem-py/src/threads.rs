//! The worker threads of a run: a rayon pool of a checked size.

use crate::errors::other;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Most worker threads per logical CPU, as the command line allows.
const MAX_PER_CPU: usize = 4;

/// A pool of `threads` workers, or of `default` (all logical CPUs when `None`); a count
/// outside `[1, 4 × CPUs]` is a ValueError naming the range.
pub fn pool(
    threads: Option<usize>,
    default: Option<usize>,
) -> PyResult<(rayon::ThreadPool, usize)> {
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let n = threads.or(default).unwrap_or(cpus);
    let max = MAX_PER_CPU * cpus;
    if n == 0 || n > max {
        return Err(PyValueError::new_err(format!(
            "threads = {n}: must lie in [1, {max}] ({MAX_PER_CPU} × the {cpus} logical CPUs of this machine)"
        )));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(other)?;
    Ok((pool, n))
}
