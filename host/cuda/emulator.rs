//! The emulated device: host memory for its buffers, and a stream that runs the kernels' host
//! builds over every thread of a launch's grid, in a shuffled order, when the work is waited on.

use crate::splitmix64::{SplitMix64, GOLDEN_GAMMA};
use coil_kernels::ptx::{Emulated, Param};
use rayon::prelude::*;
use std::mem::MaybeUninit;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

/// Threads per block of every launch.
pub(crate) const BLOCK: u32 = 256;

/// 0..n in an order drawn from `seed` (Fisher-Yates over a SplitMix64 stream).
pub(crate) fn shuffled(n: usize, seed: u64) -> Vec<usize> {
    let mut stream = SplitMix64(seed);
    let mut order: Vec<usize> = (0..n).collect();
    for k in (1..n).rev() {
        order.swap(k, (stream.next_u64() % (k as u64 + 1)) as usize);
    }
    order
}

/// The emulated device: what its buffers hold, against a size where one is set, the launches
/// it has queued, which seed each launch's thread order, and the work not yet run.
pub(crate) struct Emulator {
    /// Bytes allocated and not yet freed; shared with the buffers, which give theirs back.
    pub(crate) used: Arc<AtomicUsize>,
    /// The device's size (bytes); `None` for as much as the host has.
    pub(crate) total: Option<usize>,
    pub(crate) launches: u64,
    /// Shared with the buffers, whose memory a queued launch may still use when they go.
    pub(crate) stream: Arc<Mutex<Stream>>,
}

/// The emulated device's stream: launches queued and not yet run, and the memory of buffers
/// dropped after them, freed once they have run, as a device frees in stream order.
#[derive(Default)]
pub(crate) struct Stream {
    pub(crate) launches: Vec<QueuedLaunch>,
    pub(crate) freed: Vec<Box<[u64]>>,
}

/// A launch as the emulated device queues it: its parameters' bytes copied, as a driver copies
/// them, so the host may reuse its own.
pub(crate) struct QueuedLaunch {
    pub(crate) entry: Emulated,
    pub(crate) params: Vec<Vec<MaybeUninit<u8>>>,
    pub(crate) blocks: u32,
    /// Seeds the order of its blocks and threads.
    pub(crate) seed: u64,
}

impl QueuedLaunch {
    pub(crate) fn run(self) {
        let params: Vec<Param> = self
            .params
            .iter()
            // SAFETY: the bytes outlive the launch, which returns before they go.
            .map(|p| unsafe { Param::from_raw(p.as_ptr().cast(), p.len()) })
            .collect();
        let (entry, seed) = (self.entry, self.seed);
        // A device runs blocks and the warps in them in no set order: each launch shuffles
        // both, from its own seed, so that a kernel whose result depends on the order differs
        // from the CPU and fails the tests.
        shuffled(self.blocks as usize, seed).into_par_iter().for_each(|block| {
            for t in shuffled(BLOCK as usize, seed ^ (block as u64 + 1).wrapping_mul(GOLDEN_GAMMA)) {
                // SAFETY: as for the device: the caller of `Gpu::launch` vouched for the
                // arguments and views, whose memory a dropped buffer keeps until this has run.
                unsafe { entry(block * BLOCK as usize + t, &params) };
            }
        });
    }
}

/// The stream, locked; a launch that panicked (a kernel's bounds check) left it usable.
pub(crate) fn lock(stream: &Mutex<Stream>) -> MutexGuard<'_, Stream> {
    stream.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Host memory that kernels on the emulated device write through raw pointers, as device
/// memory is written: it is held by pointer, never borrowed for longer than one copy. In words,
/// so that every element type is aligned.
pub struct HostMemory {
    pub(crate) words: *mut u64,
    pub(crate) len: usize,
    /// The bytes asked for, which the device counts as in use until the buffer is dropped.
    bytes: usize,
    used: Arc<AtomicUsize>,
    /// Where a buffer dropped while launches are queued leaves its memory.
    stream: Arc<Mutex<Stream>>,
}

// SAFETY: the memory is owned; the run that owns the buffer is the only one to reach it.
unsafe impl Send for HostMemory {}

impl HostMemory {
    pub(crate) fn zeroed(bytes: usize, emulator: &Emulator) -> Self {
        let words: Box<[u64]> = vec![0; bytes.div_ceil(8).max(1)].into_boxed_slice();
        let len = words.len();
        emulator.used.fetch_add(bytes, Ordering::Relaxed);
        let (used, stream) = (emulator.used.clone(), emulator.stream.clone());
        Self { words: Box::into_raw(words).cast(), len, bytes, used, stream }
    }
}

impl Drop for HostMemory {
    fn drop(&mut self) {
        // SAFETY: `words` came from `Box::into_raw` of `len` words, and is dropped once.
        let words = unsafe { Box::from_raw(std::ptr::slice_from_raw_parts_mut(self.words, self.len)) };
        let mut stream = lock(&self.stream);
        if !stream.launches.is_empty() {
            stream.freed.push(words);
        }
        self.used.fetch_sub(self.bytes, Ordering::Relaxed);
    }
}
