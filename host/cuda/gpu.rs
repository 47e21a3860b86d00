//! The CUDA device of a run: its context and stream, the kernels' PTX module (compiled by
//! build.rs from `kernels/`), launches by kernel name, and allocations with clear errors.
//!
//! [`Gpu::emulated`] stands in for a device where there is none: its memory is host memory and
//! a launch runs the kernels' host builds (`coil_kernels::ptx::ENTRIES`) over every thread of
//! the grid with rayon, so the backend's host side runs and is tested without a GPU. As a
//! device's stream does, it runs launches later than they are queued: at the next copy,
//! synchronisation or timing mark.

use crate::splitmix64::{SplitMix64, GOLDEN_GAMMA};
use coil_kernels::ptx::{Emulated, Param, ENTRIES};
use cudarc::driver::{
    sys, CudaContext, CudaEvent, CudaFunction, CudaModule, CudaSlice, CudaStream, DevicePtr, DeviceRepr, DriverError,
    LaunchConfig, PushKernelArg,
};
use cudarc::nvrtc::Ptx;
use rayon::prelude::*;
use std::collections::HashMap;
use std::fmt;
use std::mem::MaybeUninit;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

/// The kernels crate as PTX.
pub const PTX: &str = include_str!(concat!(env!("OUT_DIR"), "/coil_kernels.ptx"));

/// The kernels compiled ahead of time: a fatbin of cubins for [`CUBIN_ARCHS`] and the PTX, which
/// the driver loads without compiling on those GPUs; empty where the build found no `ptxas`.
pub const FATBIN: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/coil_kernels.fatbin"));

/// The architectures of [`FATBIN`]'s cubins, as `sm_XY` numbers (`80,90`); empty without one.
pub const CUBIN_ARCHS: &str = env!("COIL_CUBIN_ARCHS");

/// Threads per block of every launch.
const BLOCK: u32 = 256;

/// The driver functions coil's calls reach through cudarc. cudarc looks each up at its first call
/// and panics where the driver lacks it, so [`Gpu::open`] looks them all up first: a driver too
/// old for one (the stream-ordered allocator came with CUDA 11.2) gives an error, not a panic
/// in the middle of a run. The CUDA tests check the list against what the build links.
pub const DRIVER_FUNCTIONS: &[&str] = &[
    "cuCtxDestroy_v2",
    "cuCtxGetCurrent",
    "cuCtxSetCurrent",
    "cuDeviceGet",
    "cuDeviceGetAttribute",
    "cuDeviceGetCount",
    "cuDeviceGetName",
    "cuDevicePrimaryCtxRelease_v2",
    "cuDevicePrimaryCtxRetain",
    "cuEventCreate",
    "cuEventDestroy_v2",
    "cuEventElapsedTime",
    "cuEventRecord",
    "cuEventSynchronize",
    "cuGetErrorString",
    "cuInit",
    "cuLaunchKernel",
    "cuMemAllocAsync",
    "cuMemAlloc_v2",
    "cuMemFreeAsync",
    "cuMemFree_v2",
    "cuMemGetInfo_v2",
    "cuMemcpyDtoDAsync_v2",
    "cuMemcpyDtoHAsync_v2",
    "cuMemcpyHtoDAsync_v2",
    "cuMemcpyPeerAsync",
    "cuMemsetD8Async",
    "cuModuleGetFunction",
    "cuModuleLoad",
    "cuModuleLoadData",
    "cuModuleLoadDataEx",
    "cuModuleUnload",
    "cuStreamDestroy_v2",
    "cuStreamSynchronize",
    "cuStreamWaitEvent",
];

/// The first of [`DRIVER_FUNCTIONS`] the driver library lacks.
fn missing_driver_function() -> Option<&'static str> {
    // SAFETY: only called once `is_culib_present` found the library; looks symbols up, calls none.
    let library = unsafe { sys::culib() };
    DRIVER_FUNCTIONS.iter().copied().find(|name| unsafe { library.get::<*const std::ffi::c_void>(name.as_bytes()) }.is_err())
}

/// What the driver's JIT compiler says when it refuses `ptx`, the context current: cudarc's load
/// passes no log buffer, so a refused module is loaded once more with one. `None` where the load
/// succeeds or the log is empty.
fn jit_error_log(ptx: &str) -> Option<String> {
    const LOG_BYTES: usize = 16 * 1024;
    let source = std::ffi::CString::new(ptx).ok()?;
    let mut log = vec![0u8; LOG_BYTES];
    let mut options = [sys::CUjit_option::CU_JIT_ERROR_LOG_BUFFER, sys::CUjit_option::CU_JIT_ERROR_LOG_BUFFER_SIZE_BYTES];
    // The driver reads the buffer's size from the pointer-sized value itself.
    let mut values = [log.as_mut_ptr().cast::<std::ffi::c_void>(), LOG_BYTES as *mut std::ffi::c_void];
    let mut module = std::ptr::null_mut();
    // SAFETY: the options and their values are paired as the driver reads them, the log buffer
    // is LOG_BYTES long and outlives the call, and `Gpu::open` found the function.
    let result =
        unsafe { sys::cuModuleLoadDataEx(&mut module, source.as_ptr().cast(), 2, options.as_mut_ptr(), values.as_mut_ptr()) };
    if result == sys::CUresult::CUDA_SUCCESS {
        // SAFETY: the module just loaded and nothing else holds it.
        unsafe { sys::cuModuleUnload(module) };
        return None;
    }
    let end = log.iter().position(|&b| b == 0).unwrap_or(LOG_BYTES);
    let text = String::from_utf8_lossy(&log[..end]).trim().to_string();
    (!text.is_empty()).then_some(text)
}

/// 0..n in an order drawn from `seed` (Fisher-Yates over a SplitMix64 stream).
fn shuffled(n: usize, seed: u64) -> Vec<usize> {
    let mut stream = SplitMix64(seed);
    let mut order: Vec<usize> = (0..n).collect();
    for k in (1..n).rev() {
        order.swap(k, (stream.next_u64() % (k as u64 + 1)) as usize);
    }
    order
}

/// Why the CUDA backend cannot run.
#[derive(Debug)]
pub enum CudaError {
    /// No CUDA driver library (libcuda) on this machine.
    NoDriver,
    /// The driver library lacks a function coil calls: an older driver.
    OldDriver(&'static str),
    /// The driver loaded but reports no device.
    NoDevice,
    /// A device allocation failed.
    OutOfMemory { what: String, bytes: usize, free: usize, total: usize },
    /// The driver refused the PTX module; `log` is its JIT compiler's error log, where it wrote one.
    PtxLoad { error: DriverError, log: Option<String> },
    /// A kernel is missing from the PTX module.
    MissingKernel(String),
    /// A launch, or the work queued before a synchronisation, failed.
    Launch { kernel: String, error: DriverError },
    /// Any other driver call failed.
    Driver { call: &'static str, error: DriverError },
}

impl fmt::Display for CudaError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CudaError::NoDriver => f.write_str(
                "no CUDA driver: libcuda.so was not found (install the NVIDIA driver, or add its folder to LD_LIBRARY_PATH); use --backend cpu",
            ),
            CudaError::OldDriver(function) => write!(
                f,
                "the CUDA driver lacks {function}, which coil calls: it is older than coil needs (CUDA 11.2 or newer); update the NVIDIA driver, or use --backend cpu"
            ),
            CudaError::NoDevice => f.write_str("the CUDA driver reports no device; use --backend cpu"),
            CudaError::OutOfMemory { what, bytes, free, total } => write!(
                f,
                "out of device memory allocating {what}: {bytes} bytes needed, {free} of {total} bytes free; lower the particle count (spacing, max_fluid_particles)"
            ),
            CudaError::PtxLoad { error, log } => {
                write!(f, "the CUDA driver could not load coil's PTX ({error})")?;
                if let Some(log) = log {
                    write!(f, "; its JIT compiler says: {log}")?;
                }
                f.write_str("; the driver may be older than the PTX ISA: update it, or set COIL_PTX_TARGET_CPU and rebuild")
            }
            CudaError::MissingKernel(name) => write!(f, "kernel {name} is missing from coil's PTX module (a stale build?)"),
            CudaError::Launch { kernel, error } => write!(
                f,
                "CUDA kernel {kernel} failed: {error} (kernels run asynchronously: set COIL_CUDA_SYNC=1 to name the failing one exactly)"
            ),
            CudaError::Driver { call, error } => write!(f, "CUDA call {call} failed: {error}"),
        }
    }
}

impl std::error::Error for CudaError {}

/// A kernel argument passed by value: the bytes of a `#[repr(C)]` argument struct, which the
/// PTX entry receives as `.param .b8 [size]`.
#[repr(transparent)]
pub struct ByValue<T>(pub T);
// SAFETY: every argument struct of `coil_kernels::ptx` is `#[repr(C)]` plain data (numbers and
// device pointers), laid out alike on the host and on nvptx64 (`coil_kernels::abi`: the CUDA tests
// compare the two compilers' layouts field by field).
unsafe impl<T: Copy> DeviceRepr for ByValue<T> {}

/// A CUDA device, through the driver.
struct Device {
    ctx: Arc<CudaContext>,
    stream: Arc<CudaStream>,
    module: Arc<CudaModule>,
    functions: HashMap<String, CudaFunction>,
    /// What the driver was given: the fatbin, or the PTX alone and why.
    code: KernelCode,
}

/// How the kernels reached the device.
enum KernelCode {
    /// [`FATBIN`]: a cubin where one fits the device, the PTX JIT-compiled where none does.
    Fatbin,
    /// [`PTX`] alone, JIT-compiled by the driver: the build had no `ptxas`, or the driver refused
    /// the fatbin (one older than the `ptxas` that compiled it).
    Ptx { fatbin_refused: Option<DriverError> },
}

/// Loads the kernels: [`FATBIN`] where the build made one and the driver takes it, else [`PTX`].
fn load_kernels(ctx: &Arc<CudaContext>) -> Result<(Arc<CudaModule>, KernelCode), CudaError> {
    let mut fatbin_refused = None;
    if !FATBIN.is_empty() {
        match ctx.load_module(Ptx::from_binary(FATBIN.to_vec())) {
            Ok(module) => return Ok((module, KernelCode::Fatbin)),
            Err(error) => fatbin_refused = Some(error),
        }
    }
    match ctx.load_module(Ptx::from_src(PTX)) {
        Ok(module) => Ok((module, KernelCode::Ptx { fatbin_refused })),
        Err(error) => Err(CudaError::PtxLoad { error, log: jit_error_log(PTX) }),
    }
}

/// The cubin of [`CUBIN_ARCHS`] the driver picks for a device of compute capability
/// `major.minor`: the newest of its major version not above it.
fn cubin_for(major: i32, minor: i32) -> Option<u32> {
    let device = (major * 10 + minor) as u32;
    CUBIN_ARCHS.split(',').filter_map(|a| a.parse::<u32>().ok()).filter(|&a| a / 10 == device / 10 && a <= device).max()
}

/// What runs the kernels.
enum Engine {
    Cuda(Device),
    /// The kernels' host builds, over host memory.
    Emulated(Emulator),
}

/// The emulated device: what its buffers hold, against a size where one is set, the launches
/// it has queued, which seed each launch's thread order, and the work not yet run.
struct Emulator {
    /// Bytes allocated and not yet freed; shared with the buffers, which give theirs back.
    used: Arc<AtomicUsize>,
    /// The device's size (bytes); `None` for as much as the host has.
    total: Option<usize>,
    launches: u64,
    /// Shared with the buffers, whose memory a queued launch may still use when they go.
    stream: Arc<Mutex<Stream>>,
}

/// The emulated device's stream: launches queued and not yet run, and the memory of buffers
/// dropped after them, freed once they have run, as a device frees in stream order.
#[derive(Default)]
struct Stream {
    launches: Vec<QueuedLaunch>,
    freed: Vec<Box<[u64]>>,
}

/// A launch as the emulated device queues it: its parameters' bytes copied, as a driver copies
/// them, so the host may reuse its own.
struct QueuedLaunch {
    entry: Emulated,
    params: Vec<Vec<MaybeUninit<u8>>>,
    blocks: u32,
    /// Seeds the order of its blocks and threads.
    seed: u64,
}

impl QueuedLaunch {
    fn run(self) {
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
fn lock(stream: &Mutex<Stream>) -> MutexGuard<'_, Stream> {
    stream.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

pub struct Gpu {
    engine: Engine,
    /// Synchronise after every launch, so a failure names its kernel (COIL_CUDA_SYNC=1).
    sync_each_launch: bool,
    last_kernel: &'static str,
    /// While profiling: each launch's kernel and the marks recorded around it.
    profile: Option<Vec<(&'static str, Mark, Mark)>>,
}

/// Bytes of device memory, or of host memory on the emulated device.
pub enum Buffer {
    Device(CudaSlice<u8>),
    Host(HostMemory),
}

/// Host memory that kernels on the emulated device write through raw pointers, as device
/// memory is written: it is held by pointer, never borrowed for longer than one copy. In words,
/// so that every element type is aligned.
pub struct HostMemory {
    words: *mut u64,
    len: usize,
    /// The bytes asked for, which the device counts as in use until the buffer is dropped.
    bytes: usize,
    used: Arc<AtomicUsize>,
    /// Where a buffer dropped while launches are queued leaves its memory.
    stream: Arc<Mutex<Stream>>,
}

// SAFETY: the memory is owned; the run that owns the buffer is the only one to reach it.
unsafe impl Send for HostMemory {}

impl HostMemory {
    fn zeroed(bytes: usize, emulator: &Emulator) -> Self {
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

/// A point in a stream's work, for timing: an event on a device, an instant on the emulated
/// one, which runs its queued launches first.
pub enum Mark {
    Event(CudaEvent),
    Instant(Instant),
}

/// GPU time of one kernel over a profiled stretch.
#[derive(Debug, Clone, PartialEq)]
pub struct KernelTime {
    pub kernel: &'static str,
    pub launches: usize,
    /// Summed over its launches (ms).
    pub total_ms: f64,
}

impl Gpu {
    /// Opens device 0 and loads the kernels. Checks for the driver library and its functions
    /// first: cudarc's loader panics without them.
    pub fn open() -> Result<Self, CudaError> {
        // SAFETY: only tries to open the library.
        if !unsafe { sys::is_culib_present() } {
            return Err(CudaError::NoDriver);
        }
        if let Some(function) = missing_driver_function() {
            return Err(CudaError::OldDriver(function));
        }
        let count = CudaContext::device_count().map_err(|error| match error.0 {
            sys::cudaError_enum::CUDA_ERROR_NO_DEVICE => CudaError::NoDevice,
            _ => CudaError::Driver { call: "cuDeviceGetCount", error },
        })?;
        if count < 1 {
            return Err(CudaError::NoDevice);
        }
        let ctx = CudaContext::new(0).map_err(|error| CudaError::Driver { call: "cuCtxCreate", error })?;
        // One stream runs everything in order; cudarc's per-buffer events would only cost time.
        // SAFETY: no buffer is used from a second stream.
        unsafe { ctx.disable_event_tracking() };
        let stream = ctx.default_stream();
        let (module, code) = load_kernels(&ctx)?;
        let sync_each_launch = std::env::var("COIL_CUDA_SYNC").is_ok_and(|v| v == "1");
        let device = Device { ctx, stream, module, functions: HashMap::new(), code };
        Ok(Self { engine: Engine::Cuda(device), sync_each_launch, last_kernel: "(none)", profile: None })
    }

    /// A device emulated on the host, for testing the backend where no GPU is: every launch
    /// runs the kernels' host builds over all threads of its grid, in parallel, its blocks and
    /// the threads of each in an order shuffled afresh each launch, as a device sets none.
    pub fn emulated() -> Self {
        Self::emulate(None)
    }

    /// [`Gpu::emulated`] with `total_bytes` of memory: an allocation beyond it fails as one on a
    /// device does, so that a run too large for its device is tested without one.
    pub fn emulated_with_memory(total_bytes: usize) -> Self {
        Self::emulate(Some(total_bytes))
    }

    fn emulate(total: Option<usize>) -> Self {
        let emulator = Emulator { used: Arc::new(AtomicUsize::new(0)), total, launches: 0, stream: Arc::default() };
        Self { engine: Engine::Emulated(emulator), sync_each_launch: false, last_kernel: "(none)", profile: None }
    }

    /// The device's name and compute capability, and how its kernels were compiled, for logs.
    pub fn describe(&self) -> String {
        let Engine::Cuda(d) = &self.engine else {
            return format!("emulated on the CPU ({} threads)", rayon::current_num_threads());
        };
        let name = d.ctx.name().unwrap_or_else(|_| "unknown device".into());
        let capability = d.ctx.compute_capability().ok();
        let device = match capability {
            Some((major, minor)) => format!("{name} (sm_{major}{minor})"),
            None => name,
        };
        let code = match (&d.code, capability.and_then(|(major, minor)| cubin_for(major, minor))) {
            (KernelCode::Fatbin, Some(arch)) => format!("kernels compiled ahead of time for sm_{arch}"),
            (KernelCode::Fatbin, None) => "kernels JIT-compiled from the fatbin's PTX (no cubin for this GPU)".into(),
            (KernelCode::Ptx { fatbin_refused: None }, _) => "kernels JIT-compiled from PTX (built without ptxas)".into(),
            (KernelCode::Ptx { fatbin_refused: Some(error) }, _) => {
                format!("kernels JIT-compiled from PTX (the driver refused the fatbin: {error})")
            }
        };
        format!("{device}, {code}")
    }

    /// The device's peak floating-point rates, from its multiprocessors, clock and
    /// architecture; none on the emulated device or where the driver does not say.
    pub fn peak_rates(&self) -> Option<super::peak_rates::PeakRates> {
        let Engine::Cuda(d) = &self.engine else {
            return None;
        };
        let attribute = |a| d.ctx.attribute(a).ok().filter(|&v| v > 0).map(f64::from);
        let multiprocessors = attribute(sys::CUdevice_attribute::CU_DEVICE_ATTRIBUTE_MULTIPROCESSOR_COUNT)?;
        // The peak clock, in kHz.
        let clock_hz = attribute(sys::CUdevice_attribute::CU_DEVICE_ATTRIBUTE_CLOCK_RATE)? * 1e3;
        super::peak_rates::PeakRates::of(d.ctx.compute_capability().ok()?, multiprocessors, clock_hz)
    }

    /// (free, total) bytes of device memory; none known on an emulated device of no set size.
    pub fn memory(&self) -> (usize, usize) {
        match &self.engine {
            Engine::Cuda(d) => d.ctx.mem_get_info().unwrap_or((0, 0)),
            Engine::Emulated(Emulator { used, total: Some(total), .. }) => {
                (total.saturating_sub(used.load(Ordering::Relaxed)), *total)
            }
            Engine::Emulated(Emulator { total: None, .. }) => (0, 0),
        }
    }

    /// `bytes` zeroed bytes of device memory; `what` names them in an out-of-memory error.
    pub fn zeros(&self, bytes: usize, what: &str) -> Result<Buffer, CudaError> {
        let out_of_memory = |bytes| {
            let (free, total) = self.memory();
            CudaError::OutOfMemory { what: what.into(), bytes, free, total }
        };
        match &self.engine {
            // A zero-length allocation is an error in the driver.
            Engine::Cuda(d) => d.stream.alloc_zeros::<u8>(bytes.max(1)).map(Buffer::Device).map_err(|error| {
                if error.0 == sys::cudaError_enum::CUDA_ERROR_OUT_OF_MEMORY {
                    out_of_memory(bytes.max(1))
                } else {
                    CudaError::Driver { call: "cuMemAlloc", error }
                }
            }),
            Engine::Emulated(memory) => {
                if memory.total.is_some_and(|total| memory.used.load(Ordering::Relaxed) + bytes > total) {
                    return Err(out_of_memory(bytes));
                }
                Ok(Buffer::Host(HostMemory::zeroed(bytes, memory)))
            }
        }
    }

    /// Copies `host` into the start of `device`.
    pub fn upload(&self, host: &[u8], device: &mut Buffer) -> Result<(), CudaError> {
        if host.is_empty() {
            return Ok(());
        }
        match (&self.engine, device) {
            (Engine::Cuda(d), Buffer::Device(slice)) => {
                let mut target = slice.slice_mut(..host.len());
                d.stream.memcpy_htod(host, &mut target).map_err(|error| self.failed("cuMemcpyHtoD", error))
            }
            (_, device) => {
                self.run_queued();
                device.host_bytes_mut()[..host.len()].copy_from_slice(host);
                Ok(())
            }
        }
    }

    /// Copies the first `host.len()` bytes of `device` into `host`, then waits for the stream:
    /// a copy into pageable memory returns once done, as CUDA documents it, but the explicit
    /// wait does not rest on that, and a fault of the kernels before the copy surfaces here.
    pub fn download(&self, device: &Buffer, host: &mut [u8]) -> Result<(), CudaError> {
        if host.is_empty() {
            return Ok(());
        }
        match (&self.engine, device) {
            (Engine::Cuda(d), Buffer::Device(slice)) => {
                d.stream.memcpy_dtoh(&slice.slice(..host.len()), host).map_err(|error| self.failed("cuMemcpyDtoH", error))?;
                d.stream.synchronize().map_err(|error| self.failed("cuStreamSynchronize", error))
            }
            (_, device) => {
                self.run_queued();
                host.copy_from_slice(&device.host_bytes()[..host.len()]);
                Ok(())
            }
        }
    }

    /// On the emulated device, fills `device` with 0xFF bytes (NaN in every float, u32::MAX in
    /// every index), so that a kernel or copy that reads what it should not have kept, a scratch
    /// array after a swap, reads nonsense and fails the tests; a GPU's memory is left as it is.
    pub fn poison(&self, device: &mut Buffer) {
        if let (Engine::Emulated(_), device) = (&self.engine, device) {
            self.run_queued();
            device.host_bytes_mut().fill(0xFF);
        }
    }

    /// Zeroes `device`.
    pub fn clear(&self, device: &mut Buffer) -> Result<(), CudaError> {
        match (&self.engine, device) {
            (Engine::Cuda(d), Buffer::Device(slice)) => {
                d.stream.memset_zeros(slice).map_err(|error| self.failed("cuMemsetD8", error))
            }
            (_, device) => {
                self.run_queued();
                device.host_bytes_mut().fill(0);
                Ok(())
            }
        }
    }

    /// Copies all of `source` into `target`, of the same size.
    fn copy(&self, source: &Buffer, target: &mut Buffer) -> Result<(), CudaError> {
        match (&self.engine, source, target) {
            (Engine::Cuda(d), Buffer::Device(s), Buffer::Device(t)) => {
                d.stream.memcpy_dtod(s, t).map_err(|error| self.failed("cuMemcpyDtoD", error))
            }
            (_, source, target) => {
                self.run_queued();
                target.host_bytes_mut().copy_from_slice(source.host_bytes());
                Ok(())
            }
        }
    }

    /// Waits for all queued work.
    pub fn synchronize(&self) -> Result<(), CudaError> {
        match &self.engine {
            Engine::Cuda(d) => d.stream.synchronize().map_err(|error| self.failed("cuStreamSynchronize", error)),
            Engine::Emulated(_) => {
                self.run_queued();
                Ok(())
            }
        }
    }

    /// Runs the emulated device's queued launches, in order, then frees what buffers dropped
    /// meanwhile held.
    fn run_queued(&self) {
        if let Engine::Emulated(emulator) = &self.engine {
            let mut stream = lock(&emulator.stream);
            for launch in std::mem::take(&mut stream.launches) {
                launch.run();
            }
            stream.freed.clear();
        }
    }

    /// A timing mark recorded now on the stream.
    pub fn mark(&self) -> Result<Mark, CudaError> {
        match &self.engine {
            Engine::Cuda(d) => d
                .stream
                .record_event(Some(sys::CUevent_flags::CU_EVENT_DEFAULT))
                .map(Mark::Event)
                .map_err(|error| CudaError::Driver { call: "cuEventRecord", error }),
            Engine::Emulated(_) => {
                self.run_queued();
                Ok(Mark::Instant(Instant::now()))
            }
        }
    }

    /// Milliseconds of GPU time between two marks from `mark` (waits for `end`).
    pub fn elapsed_ms(&self, start: &Mark, end: &Mark) -> Result<f64, CudaError> {
        match (start, end) {
            (Mark::Event(start), Mark::Event(end)) => {
                start.elapsed_ms(end).map(f64::from).map_err(|error| self.failed("cuEventElapsedTime", error))
            }
            (Mark::Instant(start), Mark::Instant(end)) => Ok(end.duration_since(*start).as_secs_f64() * 1e3),
            _ => unreachable!("marks of one device are of one kind"),
        }
    }

    /// Device-to-device copy bandwidth (bytes/s, read plus write): the median of 5 copies of
    /// 256 MiB, or of a quarter of free memory where that is less.
    pub fn copy_bandwidth(&self) -> Result<f64, CudaError> {
        let bytes = (256usize << 20).min(self.memory().0 / 4).max(1 << 20);
        let source = self.zeros(bytes, "bandwidth probe")?;
        let mut target = self.zeros(bytes, "bandwidth probe")?;
        let mut rates = Vec::new();
        for _ in 0..5 {
            let start = self.mark()?;
            self.copy(&source, &mut target)?;
            let end = self.mark()?;
            rates.push(2.0 * bytes as f64 / (self.elapsed_ms(&start, &end)? * 1e-3));
        }
        rates.sort_by(f64::total_cmp);
        Ok(rates[2])
    }

    /// Starts timing every launch with CUDA events.
    pub fn start_profile(&mut self) {
        self.profile = Some(Vec::new());
    }

    /// Stops timing launches and returns each kernel's GPU time since `start_profile`, in the
    /// order of first launch.
    pub fn finish_profile(&mut self) -> Result<Vec<KernelTime>, CudaError> {
        let launches = self.profile.take().unwrap_or_default();
        let mut times: Vec<KernelTime> = Vec::new();
        for (kernel, start, end) in &launches {
            let ms = self.elapsed_ms(start, end)?;
            match times.iter_mut().find(|t| t.kernel == *kernel) {
                Some(t) => {
                    t.launches += 1;
                    t.total_ms += ms;
                }
                None => times.push(KernelTime { kernel, launches: 1, total_ms: ms }),
            }
        }
        Ok(times)
    }

    /// The device address of `buffer`, for the views inside kernel arguments.
    pub fn address(&self, buffer: &Buffer) -> u64 {
        match (&self.engine, buffer) {
            (Engine::Cuda(d), Buffer::Device(slice)) => slice.device_ptr(&d.stream).0,
            (_, Buffer::Host(memory)) => memory.words as u64,
            (Engine::Emulated(_), Buffer::Device(_)) => unreachable!("a device buffer on the emulated device"),
        }
    }

    /// Launches kernel `name` with `threads` threads and the given by-value arguments.
    ///
    /// # Safety
    /// `args` must match the PTX entry's parameters, and every view inside them must point to
    /// live device memory of the length it claims.
    pub unsafe fn launch(&mut self, name: &'static str, threads: u32, args: &[&dyn Arg]) -> Result<(), CudaError> {
        if threads == 0 {
            return Ok(());
        }
        let blocks = threads.div_ceil(BLOCK);
        self.last_kernel = name;
        let start = if self.profile.is_some() { Some(self.mark()?) } else { None };
        match &mut self.engine {
            Engine::Cuda(d) => {
                if !d.functions.contains_key(name) {
                    let f = d.module.load_function(name).map_err(|_| CudaError::MissingKernel(name.into()))?;
                    d.functions.insert(name.into(), f);
                }
                let mut builder = d.stream.launch_builder(&d.functions[name]);
                for a in args {
                    a.push(&mut builder);
                }
                let cfg = LaunchConfig { grid_dim: (blocks, 1, 1), block_dim: (BLOCK, 1, 1), shared_mem_bytes: 0 };
                builder.launch(cfg).map_err(|error| CudaError::Launch { kernel: name.into(), error })?;
                if self.sync_each_launch {
                    d.stream.synchronize().map_err(|error| CudaError::Launch { kernel: name.into(), error })?;
                }
            }
            Engine::Emulated(emulator) => {
                let entry: Emulated =
                    ENTRIES.iter().find(|(n, _)| *n == name).ok_or_else(|| CudaError::MissingKernel(name.into()))?.1;
                emulator.launches += 1;
                let params = args.iter().map(|a| a.bytes()).collect();
                lock(&emulator.stream).launches.push(QueuedLaunch { entry, params, blocks, seed: emulator.launches });
            }
        }
        if let Some(start) = start {
            let end = self.mark()?;
            self.profile.get_or_insert_with(Vec::new).push((name, start, end));
        }
        Ok(())
    }

    /// A failure found at a synchronising call: the queued kernels ran before it.
    fn failed(&self, call: &'static str, error: DriverError) -> CudaError {
        match error.0 {
            sys::cudaError_enum::CUDA_ERROR_LAUNCH_FAILED
            | sys::cudaError_enum::CUDA_ERROR_ILLEGAL_ADDRESS
            | sys::cudaError_enum::CUDA_ERROR_ILLEGAL_INSTRUCTION
            | sys::cudaError_enum::CUDA_ERROR_MISALIGNED_ADDRESS => {
                CudaError::Launch { kernel: format!("{} or a kernel before it", self.last_kernel), error }
            }
            _ => CudaError::Driver { call, error },
        }
    }
}

impl Buffer {
    /// The bytes of host memory, for one copy: no launch runs meanwhile, since the emulated
    /// device runs its queued launches, on the calling thread, before the copy.
    fn host_bytes(&self) -> &[u8] {
        match self {
            // SAFETY: `len` initialised words, owned by `self`.
            Buffer::Host(m) => unsafe { std::slice::from_raw_parts(m.words.cast(), m.len * 8) },
            Buffer::Device(_) => unreachable!("a device buffer on the emulated device"),
        }
    }

    fn host_bytes_mut(&mut self) -> &mut [u8] {
        match self {
            // SAFETY: as above, and `&mut self` excludes every other copy.
            Buffer::Host(m) => unsafe { std::slice::from_raw_parts_mut(m.words.cast(), m.len * 8) },
            Buffer::Device(_) => unreachable!("a device buffer on the emulated device"),
        }
    }
}

/// One kernel argument of [`Gpu::launch`].
pub trait Arg {
    fn push<'a>(&'a self, builder: &mut cudarc::driver::LaunchArgs<'a>);
    /// A copy of the argument's bytes, as a driver takes one at a launch (padding included,
    /// hence maybe uninitialised).
    fn bytes(&self) -> Vec<MaybeUninit<u8>>;
}

impl<T: Copy> Arg for ByValue<T> {
    fn push<'a>(&'a self, builder: &mut cudarc::driver::LaunchArgs<'a>) {
        builder.arg(self);
    }

    fn bytes(&self) -> Vec<MaybeUninit<u8>> {
        // SAFETY: any value's bytes may be read as `MaybeUninit<u8>`.
        unsafe { std::slice::from_raw_parts((&self.0 as *const T).cast(), std::mem::size_of::<T>()) }.to_vec()
    }
}
