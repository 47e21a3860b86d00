//! Counting sort of particles by cell key (Algorithm 1, line 3): histogram with atomics,
//! exclusive scan, scatter, then a per-cell sort of each run by previous index. The keys are
//! bounded cell indices, so this is the one pass of a radix sort with a radix of `cell_count + 1`.
//!
//! The atomic scatter fills each cell's run in whatever order the threads arrive; sorting the
//! (short) run by previous index makes the permutation, and so every later floating-point sum,
//! independent of scheduling: runs are bit-reproducible across thread counts and devices.

use crate::view::{View, ViewMut};
use core::marker::PhantomData;
use core::sync::atomic::{AtomicU32, Ordering};

/// Per-bucket counters updated with atomic adds (`atom.global.add` on the device).
#[repr(C)]
#[derive(Debug)]
pub struct Counters<'a> {
    pub(crate) ptr: *const AtomicU32,
    pub(crate) len: usize,
    _life: PhantomData<&'a [AtomicU32]>,
}
impl Clone for Counters<'_> {
    fn clone(&self) -> Self {
        *self
    }
}
impl Copy for Counters<'_> {}
// SAFETY: all access goes through atomics.
unsafe impl Send for Counters<'_> {}
unsafe impl Sync for Counters<'_> {}

impl<'a> Counters<'a> {
    pub fn new(s: &'a [AtomicU32]) -> Self {
        Self { ptr: s.as_ptr(), len: s.len(), _life: PhantomData }
    }

    /// # Safety
    /// `ptr` must point to `len` u32 counters that outlive the view.
    pub unsafe fn from_raw(ptr: *const AtomicU32, len: usize) -> Self {
        Self { ptr, len, _life: PhantomData }
    }

    #[inline(always)]
    fn get(&self, k: usize) -> &AtomicU32 {
        debug_assert!(k < self.len);
        // SAFETY: keys are below `cell_count + 1`, the length the backend allocates.
        unsafe { &*self.ptr.add(k) }
    }

    #[inline(always)]
    pub fn fetch_add(&self, k: usize) -> u32 {
        self.get(k).fetch_add(1, Ordering::Relaxed)
    }

    #[inline(always)]
    pub fn load(&self, k: usize) -> u32 {
        self.get(k).load(Ordering::Relaxed)
    }

    #[inline(always)]
    pub fn store(&self, k: usize, v: u32) {
        self.get(k).store(v, Ordering::Relaxed)
    }
}

/// Histogram: counts particle `i` in the bucket of its cell key.
#[inline(always)]
pub fn count_particle(i: usize, cell_key: View<u32>, counts: Counters) {
    counts.fetch_add(cell_key.at(i) as usize);
}

/// Sum of the counts in chunk `chunk` (first pass of the exclusive scan).
#[inline(always)]
pub fn chunk_total(chunk: usize, chunk_len: usize, counts: Counters) -> u32 {
    let start = chunk * chunk_len;
    let end = (start + chunk_len).min(counts.len);
    (start..end).map(|k| counts.load(k)).sum()
}

/// Exclusive scan of a level of at most `SCAN_FAN_IN` entries in place, serially: the top of
/// the scan of the chunk totals (see `scan_levels`).
#[inline(always)]
pub fn scan_chunk_offsets(totals: ViewMut<u32>) {
    let mut running = 0u32;
    for c in 0..totals.len() {
        let total = totals.at(c);
        // SAFETY: the single invocation owns every entry.
        unsafe { totals.write(c, running) };
        running += total;
    }
}

/// Chunk totals summed per level of the scan that gives their offsets.
pub const SCAN_FAN_IN: usize = 64;

/// Buckets per scan chunk on the CPU: a chunk is one rayon task, and long chunks keep a few
/// thousand tasks at a million cells, where short ones would cost more in scheduling than in
/// adding.
pub const CPU_SCAN_CHUNK: usize = 4096;

/// Buckets per scan chunk on the device: a chunk is one thread's loop, and short chunks keep it
/// short while the grid has threads to spare; their totals are scanned level by level.
pub const DEVICE_SCAN_CHUNK: usize = 64;

/// The levels of the exclusive scan of `totals` chunk totals, kept one after the other in one
/// array: level 0 holds the totals, each next level the sums of `SCAN_FAN_IN` entries of the
/// one before, up to a level of at most `SCAN_FAN_IN` entries, which one invocation scans. A
/// fine grid has many chunks (2 million cells make 34 000 chunks of 64): a single thread
/// walking them all would wait on memory for each, in series. Yields (first index, length).
pub fn scan_levels(totals: usize) -> impl Iterator<Item = (usize, usize)> {
    let mut next = Some((0, totals));
    core::iter::from_fn(move || {
        let level = next?;
        next = (level.1 > SCAN_FAN_IN).then(|| (level.0 + level.1, level.1.div_ceil(SCAN_FAN_IN)));
        Some(level)
    })
}

/// Entries of the array that holds every level of `scan_levels(totals)`.
pub fn scan_levels_len(totals: usize) -> usize {
    scan_levels(totals).map(|(_, len)| len).sum()
}

/// One launch of the scan of the chunk totals, its levels given as (first index, length) in the
/// array of [`scan_levels`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScanStep {
    /// Fill `sums` with [`sum_chunk`] of `values`, one invocation per entry of `sums`.
    Up { values: (usize, usize), sums: (usize, usize) },
    /// Scan the last level with [`scan_chunk_offsets`], one invocation.
    Top((usize, usize)),
    /// Scan `values` in place with [`scan_chunk_in_place`] from the scanned `offsets`, one
    /// invocation per entry of `offsets`.
    Down { values: (usize, usize), offsets: (usize, usize) },
}

/// Runs the scan of `totals` chunk totals over `scan_levels(totals)`: up from the totals, the
/// top, then back down; each backend launches each step its way.
pub fn scan_by_levels<E>(totals: usize, mut step: impl FnMut(ScanStep) -> Result<(), E>) -> Result<(), E> {
    let count = scan_levels(totals).count();
    let level = |k: usize| scan_levels(totals).nth(k).unwrap_or((0, 0));
    for k in 0..count - 1 {
        step(ScanStep::Up { values: level(k), sums: level(k + 1) })?;
    }
    step(ScanStep::Top(level(count - 1)))?;
    for k in (0..count - 1).rev() {
        step(ScanStep::Down { values: level(k), offsets: level(k + 1) })?;
    }
    Ok(())
}

/// Sum of chunk `chunk` of `values`, in chunks of `SCAN_FAN_IN`: one level up the scan.
#[inline(always)]
pub fn sum_chunk(chunk: usize, values: View<u32>) -> u32 {
    let start = chunk * SCAN_FAN_IN;
    let end = (start + SCAN_FAN_IN).min(values.len());
    (start..end).map(|k| values.at(k)).sum()
}

/// Exclusive scan in place of chunk `chunk` of `values`, in chunks of `SCAN_FAN_IN`, starting
/// from `offset`, the chunk's entry one level up once that level is scanned: one level down.
#[inline(always)]
pub fn scan_chunk_in_place(chunk: usize, offset: u32, values: ViewMut<u32>) {
    let start = chunk * SCAN_FAN_IN;
    let end = (start + SCAN_FAN_IN).min(values.len());
    let mut running = offset;
    for k in start..end {
        let v = values.at(k);
        // SAFETY: each chunk owns its range of entries.
        unsafe { values.write(k, running) };
        running += v;
    }
}

/// Exclusive scan of chunk `chunk`, offset by the total of all earlier chunks (second pass).
/// Writes `bucket_start[k]` for the chunk's buckets, the cursor the scatter advances
/// (`counts[k] = bucket_start[k]`), and, from the last chunk, the grand total.
#[inline(always)]
pub fn scan_chunk(chunk: usize, chunk_len: usize, chunk_offset: u32, counts: Counters, bucket_start: ViewMut<u32>) {
    let start = chunk * chunk_len;
    let end = (start + chunk_len).min(counts.len);
    let mut running = chunk_offset;
    for k in start..end {
        let c = counts.load(k);
        // SAFETY: each chunk owns its range of buckets.
        unsafe { bucket_start.write(k, running) };
        counts.store(k, running);
        running += c;
    }
    if end == counts.len {
        // SAFETY: only the last chunk writes the final entry.
        unsafe { bucket_start.write(end, running) };
    }
}

/// Scatter: places particle `i` at the next free slot of its bucket. `cursor` holds each
/// bucket's next slot (left there by [`scan_chunk`]); `order[slot]` is the particle's old index.
#[inline(always)]
pub fn scatter(i: usize, cell_key: View<u32>, cursor: Counters, order: ViewMut<u32>) {
    let slot = cursor.fetch_add(cell_key.at(i) as usize);
    // SAFETY: the atomic add hands every slot to exactly one particle.
    unsafe { order.write(slot as usize, i as u32) };
}

/// Sorts bucket `c`'s run of `order` by old index (insertion sort: runs hold ~8 particles).
#[inline(always)]
pub fn sort_bucket(c: usize, bucket_start: View<u32>, order: ViewMut<u32>) {
    let start = bucket_start.at(c) as usize;
    let end = bucket_start.at(c + 1) as usize;
    for k in start + 1..end {
        let v = order.at(k);
        let mut m = k;
        while m > start && order.at(m - 1) > v {
            // SAFETY: bucket c's run is owned by this invocation.
            unsafe { order.write(m, order.at(m - 1)) };
            m -= 1;
        }
        // SAFETY: as above.
        unsafe { order.write(m, v) };
    }
}

/// Reorder: entry `k` of the sorted array is entry `order[k]` of the unsorted one.
#[inline(always)]
pub fn gather<T: Copy>(k: usize, order: View<u32>, unsorted: View<T>, sorted: ViewMut<T>) {
    // SAFETY: each k is written by one invocation.
    unsafe { sorted.write(k, unsorted.at(order.at(k) as usize)) };
}

/// One array of a [`ReorderArgs`] launch: `unsorted` gathered into `sorted`, or nothing where
/// `sorted` is empty.
#[repr(C)]
#[derive(Debug)]
pub struct Gathered<'a, T> {
    pub unsorted: View<'a, T>,
    pub sorted: ViewMut<'a, T>,
}
impl<T> Clone for Gathered<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Gathered<'_, T> {}

impl<'a, T: Copy> Gathered<'a, T> {
    pub fn new(unsorted: View<'a, T>, sorted: ViewMut<'a, T>) -> Self {
        Self { unsorted, sorted }
    }

    /// No array: the launch skips it.
    pub fn none() -> Self {
        Self { unsorted: View::new(&[]), sorted: ViewMut::new(&mut []) }
    }

    #[inline(always)]
    fn gather(&self, k: usize, from: usize) {
        if !self.sorted.is_empty() {
            // SAFETY: each k is written by one invocation.
            unsafe { self.sorted.write(k, self.unsorted.at(from)) };
        }
    }
}

/// The arrays one launch of the device's reorder gathers by `order`: a position axis (f64), two
/// arrays of `R` and the ids. One launch an array would leave a small run's step bound by
/// launches rather than bytes.
#[repr(C)]
#[derive(Debug)]
pub struct ReorderArgs<'a, R> {
    pub order: View<'a, u32>,
    pub wide: Gathered<'a, f64>,
    pub first: Gathered<'a, R>,
    pub second: Gathered<'a, R>,
    pub index: Gathered<'a, u32>,
}
impl<R> Clone for ReorderArgs<'_, R> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<R> Copy for ReorderArgs<'_, R> {}

/// [`gather`] of entry `k` of every array of `args`.
#[inline(always)]
pub fn reorder_pass<R: Copy>(k: usize, args: &ReorderArgs<R>) {
    let from = args.order.at(k) as usize;
    args.wide.gather(k, from);
    args.first.gather(k, from);
    args.second.gather(k, from);
    args.index.gather(k, from);
}
