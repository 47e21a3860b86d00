//! The CPU backend's launcher: a kernel function over all indices, in parallel with rayon.

use rayon::prelude::*;

/// Runs `kernel(i)` for every `i < n`. Each index is computed by the same function whatever
/// thread runs it, so results do not depend on the thread count.
pub fn launch(n: usize, kernel: impl Fn(usize) + Sync + Send) {
    (0..n).into_par_iter().with_min_len(256).for_each(kernel);
}

/// Runs `body` on a thread of rayon's pool, so that the launches inside it fork from a worker
/// instead of each handing its job to the pool from outside and sleeping until it is done: a
/// step launches about twenty passes, and at a few thousand particles that hand-over (a wake-up
/// and a sleep per launch) cost more than the passes.
pub fn on_worker<T: Send>(body: impl FnOnce() -> T + Send) -> T {
    if rayon::current_thread_index().is_some() {
        body()
    } else {
        rayon::scope(|_| body())
    }
}

#[cfg(test)]
mod tests {
    use super::on_worker;

    #[test]
    fn on_worker_runs_a_body_from_outside_the_pool_on_one_of_its_threads() {
        assert_eq!(rayon::current_thread_index(), None, "the test harness's thread is not a worker");
        assert!(on_worker(rayon::current_thread_index).is_some());
    }
}
