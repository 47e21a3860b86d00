//! The CPU backend's launcher: a kernel function over all indices, in parallel with rayon.

use rayon::prelude::*;

/// Runs `kernel(i)` for every `i < n`. Each index is computed by the same function whatever
/// thread runs it, so results do not depend on the thread count.
pub fn launch(n: usize, kernel: impl Fn(usize) + Sync + Send) {
    (0..n).into_par_iter().with_min_len(256).for_each(kernel);
}
