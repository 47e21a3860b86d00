//! A stand-in CUDA driver for coil's tests: a `libcuda.so` with every driver function coil calls
//! (`coil::cuda::gpu::DRIVER_FUNCTIONS`), so that a `cuda` build runs its real path, cudarc's
//! marshalling and all, where no GPU is.
//!
//! Device memory is host memory, filled with 0xFF bytes when allocated (a GPU's is not zeroed).
//! A module is coil's PTX, alone or in an uncompressed fatbin (which must hold a cubin for this
//! device, sm_90, or the PTX): the stand-in reads each entry's parameter sizes from the PTX, and
//! a launch runs the kernels' host builds (`coil_kernels::ptx::find_entry`) by name over every
//! thread of its grid, each parameter checked against its entry's type. Work on the stream
//! (launches, copies, sets, frees, events) is queued and runs only at a synchronisation, as on
//! a GPU, so a host read that does not wait reads nothing, and a kernel that reads outside its
//! arrays is an illegal address there.
//!
//! The environment asks for the failures a GPU gives:
//! - `FAKE_CUDA_DEVICES`: the devices reported (default 1); with none, `cuInit` fails as a
//!   driver with no device does.
//! - `FAKE_CUDA_MEMORY_BYTES`: the device's memory (default 80 GiB).
//! - `FAKE_CUDA_OOM_AT=n`: the n-th allocation fails, out of memory.
//! - `FAKE_CUDA_ILLEGAL_ADDRESS_AT_SYNC=n`: the n-th synchronisation reports an illegal address,
//!   and so does every call after it, as a context that faulted does.
//! - `FAKE_CUDA_ILLEGAL_ADDRESS_AT_LAUNCH=n`: the n-th launch faults when it runs, and the
//!   stand-in names its kernel on stderr (`fake CUDA: kernel NAME faulted`).
//! - `FAKE_CUDA_REFUSE=fatbin`: a fatbin is refused, as a driver older than the `ptxas` that
//!   compiled it refuses it; `=all`: PTX too, as a driver older than its ISA, with a JIT log.

use coil_kernels::ptx::{find_entry, Emulated, Param};
use rayon::prelude::*;
use std::collections::HashMap;
use std::ffi::{c_char, c_int, c_uint, c_void, CStr};
use std::mem::MaybeUninit;
use std::panic::AssertUnwindSafe;
use std::sync::{Mutex, MutexGuard};
use std::time::Instant;

type CuResult = c_int;
const SUCCESS: CuResult = 0;
const INVALID_VALUE: CuResult = 1;
const OUT_OF_MEMORY: CuResult = 2;
const NO_DEVICE: CuResult = 100;
const INVALID_IMAGE: CuResult = 200;
const NO_BINARY_FOR_GPU: CuResult = 209;
const UNSUPPORTED_PTX_VERSION: CuResult = 222;
const NOT_FOUND: CuResult = 500;
const NOT_READY: CuResult = 600;
const ILLEGAL_ADDRESS: CuResult = 700;
const NOT_SUPPORTED: CuResult = 801;

/// The device: an H100's compute capability, multiprocessors and clock.
const ARCH: u32 = 90;
const MULTIPROCESSORS: c_int = 132;
const CLOCK_KHZ: c_int = 1_980_000;
const NAME: &CStr = c"coil fake CUDA device";
const DEFAULT_MEMORY_BYTES: usize = 80 << 30;

/// What the JIT log says where `FAKE_CUDA_REFUSE=all`.
const JIT_LOG: &str = "ptxas application ptx input, line 3; fatal   : Unsupported .version 7.0; current version is '6.4'";

/// `CUdevice_attribute` values the stand-in answers; every other attribute reads 0.
mod attribute {
    pub const CLOCK_RATE: i32 = 13;
    pub const MULTIPROCESSOR_COUNT: i32 = 16;
    pub const COMPUTE_CAPABILITY_MAJOR: i32 = 75;
    pub const COMPUTE_CAPABILITY_MINOR: i32 = 76;
    pub const MEMORY_POOLS_SUPPORTED: i32 = 115;
}

/// `CUjit_option` values of the JIT's error log.
const JIT_ERROR_LOG_BUFFER: c_int = 5;
const JIT_ERROR_LOG_BUFFER_SIZE_BYTES: c_int = 6;

fn env_number(name: &str) -> Option<usize> {
    std::env::var(name).ok()?.parse().ok()
}

/// A kernel of a loaded module: its host build and its parameters' sizes from the PTX.
struct Kernel {
    name: String,
    entry: Emulated,
    param_sizes: Vec<usize>,
}

/// A loaded module: each PTX entry's parameter sizes, by name.
struct Module {
    entries: HashMap<String, Vec<usize>>,
}

/// Work queued on the stream. Addresses are device addresses (of host memory).
enum Op {
    Launch {
        kernel: &'static Kernel,
        threads: usize,
        /// Copied at the launch, padding and all (hence maybe uninitialised).
        params: Vec<Vec<MaybeUninit<u8>>>,
        faults: bool,
    },
    /// The host's bytes, taken when the copy was queued, as a driver stages a pageable copy.
    Upload {
        to: u64,
        bytes: Vec<u8>,
    },
    Download {
        to: usize,
        from: u64,
        bytes: usize,
    },
    Copy {
        to: u64,
        from: u64,
        bytes: usize,
    },
    Set {
        to: u64,
        value: u8,
        bytes: usize,
    },
    Free(u64),
    Record(usize),
}

#[derive(Default)]
struct Driver {
    /// Live allocations by address, as words so that every element type is aligned.
    memory: HashMap<u64, Box<[u64]>>,
    used_bytes: usize,
    allocations: usize,
    launches: usize,
    synchronisations: usize,
    /// Set by a fault: every call fails from then on.
    lost: bool,
    queue: Vec<Op>,
    /// Each event's time, once the stream reached it.
    events: Vec<Option<Instant>>,
    current_context: usize,
}

static DRIVER: Mutex<Option<Driver>> = Mutex::new(None);

/// The driver's state, locked; a call that panicked elsewhere left it usable.
fn driver() -> MutexGuard<'static, Option<Driver>> {
    DRIVER.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Runs `call` on the driver's state, failing as a lost context does where one faulted.
fn with_driver(call: impl FnOnce(&mut Driver) -> CuResult) -> CuResult {
    let mut guard = driver();
    let driver = guard.get_or_insert_with(Driver::default);
    if driver.lost {
        return ILLEGAL_ADDRESS;
    }
    call(driver)
}

impl Driver {
    fn total_bytes() -> usize {
        env_number("FAKE_CUDA_MEMORY_BYTES").unwrap_or(DEFAULT_MEMORY_BYTES)
    }

    fn allocate(&mut self, bytes: usize, address: *mut u64) -> CuResult {
        self.allocations += 1;
        let refused = env_number("FAKE_CUDA_OOM_AT") == Some(self.allocations);
        if refused || self.used_bytes + bytes > Self::total_bytes() {
            return OUT_OF_MEMORY;
        }
        if bytes == 0 || address.is_null() {
            return INVALID_VALUE;
        }
        let words = vec![u64::MAX; bytes.div_ceil(8)].into_boxed_slice();
        let at = words.as_ptr() as u64;
        self.memory.insert(at, words);
        self.used_bytes += bytes;
        // SAFETY: the caller's out-parameter, checked non-null.
        unsafe { *address = at };
        SUCCESS
    }

    /// The `bytes` bytes at device address `at`, where one allocation holds them all.
    fn region(&mut self, at: u64, bytes: usize) -> Option<*mut u8> {
        let (&start, words) =
            self.memory.iter_mut().find(|(&start, words)| at >= start && at - start < 8 * words.len() as u64)?;
        let offset = (at - start) as usize;
        (offset + bytes <= 8 * words.len()).then(|| words.as_mut_ptr().cast::<u8>().wrapping_add(offset))
    }

    /// Runs the queued work in order; a fault loses the context.
    fn synchronise(&mut self) -> CuResult {
        self.synchronisations += 1;
        let injected = env_number("FAKE_CUDA_ILLEGAL_ADDRESS_AT_SYNC") == Some(self.synchronisations);
        let queue = std::mem::take(&mut self.queue);
        let ran = queue.into_iter().try_for_each(|op| self.run(op));
        if injected || ran.is_err() {
            self.lost = true;
            return ILLEGAL_ADDRESS;
        }
        SUCCESS
    }

    fn run(&mut self, op: Op) -> Result<(), ()> {
        match op {
            Op::Launch { kernel, faults: true, .. } => {
                eprintln!("fake CUDA: kernel {} faulted", kernel.name);
                Err(())
            }
            Op::Launch { kernel, threads, params, faults: false } => {
                let params: Vec<Param> = params
                    .iter()
                    // SAFETY: the bytes outlive the launch, which returns before they go.
                    .map(|p| unsafe { Param::from_raw(p.as_ptr().cast(), p.len()) })
                    .collect();
                let entry = kernel.entry;
                // A kernel reading past an array panics on the host (the views check their
                // indices off the device); on a GPU that is an illegal address.
                std::panic::catch_unwind(AssertUnwindSafe(|| {
                    // SAFETY: the parameters are the entry's, sized as the PTX declares them
                    // (the entry checks each against its type); their views are the caller's.
                    (0..threads).into_par_iter().for_each(|i| unsafe { entry(i, &params) })
                }))
                .map_err(|_| eprintln!("fake CUDA: kernel {} faulted", kernel.name))
            }
            Op::Upload { to, bytes } => {
                let target = self.region(to, bytes.len()).ok_or(())?;
                // SAFETY: `region` found `bytes.len()` bytes of one allocation at `target`.
                unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), target, bytes.len()) };
                Ok(())
            }
            Op::Download { to, from, bytes } => {
                let source = self.region(from, bytes).ok_or(())?;
                // SAFETY: the caller's host buffer of `bytes` bytes, as cuMemcpyDtoH's contract.
                unsafe { std::ptr::copy_nonoverlapping(source, to as *mut u8, bytes) };
                Ok(())
            }
            Op::Copy { to, from, bytes } => {
                let source = self.region(from, bytes).ok_or(())?;
                let target = self.region(to, bytes).ok_or(())?;
                // SAFETY: both found within allocations; `copy` allows overlap.
                unsafe { std::ptr::copy(source, target, bytes) };
                Ok(())
            }
            Op::Set { to, value, bytes } => {
                let target = self.region(to, bytes).ok_or(())?;
                // SAFETY: found within an allocation.
                unsafe { std::ptr::write_bytes(target, value, bytes) };
                Ok(())
            }
            Op::Free(at) => self.free(at),
            Op::Record(event) => {
                *self.events.get_mut(event).ok_or(())? = Some(Instant::now());
                Ok(())
            }
        }
    }

    fn free(&mut self, at: u64) -> Result<(), ()> {
        let words = self.memory.remove(&at).ok_or(())?;
        self.used_bytes = self.used_bytes.saturating_sub(8 * words.len());
        Ok(())
    }
}

/// The images of a fatbin: (kind, sm, bytes), kind 1 PTX and 2 ELF; `None` where it is not one
/// this stand-in reads (compressed images included).
fn fatbin_images(fatbin: *const u8) -> Option<Vec<(u16, u32, &'static [u8])>> {
    // SAFETY: the caller's image starts with the fatbin header, whose sizes bound the rest.
    let read = |offset: usize, bytes: usize| unsafe { std::slice::from_raw_parts(fatbin.add(offset), bytes) };
    let header = read(0, 16);
    let header_bytes = u16::from_le_bytes([header[6], header[7]]) as usize;
    let payload_bytes = u64::from_le_bytes(header[8..16].try_into().ok()?) as usize;
    let mut images = Vec::new();
    let mut at = header_bytes;
    while at < header_bytes + payload_bytes {
        let entry = read(at, 48);
        let kind = u16::from_le_bytes([entry[0], entry[1]]);
        let entry_bytes = u32::from_le_bytes(entry[4..8].try_into().ok()?) as usize;
        let bytes = u64::from_le_bytes(entry[8..16].try_into().ok()?) as usize;
        let sm = u32::from_le_bytes(entry[28..32].try_into().ok()?);
        let flags = u64::from_le_bytes(entry[40..48].try_into().ok()?);
        const COMPRESSED: u64 = 0x2000 | 0x8000;
        if flags & COMPRESSED != 0 {
            return None;
        }
        images.push((kind, sm, read(at + entry_bytes, bytes)));
        at += entry_bytes + bytes;
    }
    Some(images)
}

/// Each `.visible .entry` of `ptx` and its parameters' sizes in bytes.
fn ptx_entries(ptx: &str) -> Option<HashMap<String, Vec<usize>>> {
    let mut entries = HashMap::new();
    let mut lines = ptx.lines();
    while let Some(line) = lines.next() {
        let Some(name) = line.trim().strip_prefix(".visible .entry ") else { continue };
        let mut sizes = Vec::new();
        for param in lines.by_ref().map(str::trim) {
            if param.starts_with(')') {
                break;
            }
            sizes.push(param_size(param)?);
        }
        entries.insert(name.trim_end_matches('(').to_string(), sizes);
    }
    Some(entries)
}

/// `.param .align 8 .b8 name[48],` is 48 bytes; `.param .u32 name,` 4.
fn param_size(param: &str) -> Option<usize> {
    if let Some(open) = param.find('[') {
        return param[open + 1..].split(']').next()?.parse().ok();
    }
    let kind = param.split_whitespace().nth(1)?;
    let bits: usize = kind.trim_start_matches(|c: char| c == '.' || c.is_ascii_alphabetic()).parse().ok()?;
    Some(bits / 8)
}

/// Loads `image` (PTX text or a fatbin) as the device would; where refused, writes `log`.
fn load(module: *mut *mut c_void, image: *const c_void, log: Option<&mut [u8]>) -> CuResult {
    let refuse = std::env::var("FAKE_CUDA_REFUSE").unwrap_or_default();
    let image = image.cast::<u8>();
    // SAFETY: the caller's image; a fatbin's header is at least 16 bytes, PTX text longer.
    let magic = u32::from_le_bytes(unsafe { std::slice::from_raw_parts(image, 4) }.try_into().expect("4 bytes"));
    let ptx: &str = if magic == 0xBA55_ED50 {
        if refuse == "fatbin" || refuse == "all" {
            return NO_BINARY_FOR_GPU;
        }
        let Some(images) = fatbin_images(image) else { return INVALID_IMAGE };
        let cubin = images.iter().any(|&(kind, sm, bytes)| kind == 2 && sm == ARCH && bytes.starts_with(b"\x7fELF"));
        let Some(ptx) = images.iter().find(|&&(kind, _, _)| kind == 1).map(|&(_, _, bytes)| bytes) else {
            return INVALID_IMAGE;
        };
        if !cubin {
            return NO_BINARY_FOR_GPU;
        }
        let end = ptx.iter().position(|&b| b == 0).unwrap_or(ptx.len());
        match std::str::from_utf8(&ptx[..end]) {
            Ok(text) => text,
            Err(_) => return INVALID_IMAGE,
        }
    } else {
        if refuse == "all" {
            if let Some(log) = log.filter(|l| !l.is_empty()) {
                let n = JIT_LOG.len().min(log.len() - 1);
                log[..n].copy_from_slice(&JIT_LOG.as_bytes()[..n]);
                log[n] = 0;
            }
            return UNSUPPORTED_PTX_VERSION;
        }
        // SAFETY: PTX text is NUL-terminated, as cuModuleLoadData requires.
        match unsafe { CStr::from_ptr(image.cast()) }.to_str() {
            Ok(text) => text,
            Err(_) => return INVALID_IMAGE,
        }
    };
    let Some(entries) = ptx_entries(ptx) else { return INVALID_IMAGE };
    with_driver(|_| {
        // SAFETY: the caller's out-parameter.
        unsafe { *module = Box::into_raw(Box::new(Module { entries })).cast() };
        SUCCESS
    })
}

#[no_mangle]
pub extern "C" fn cuInit(_flags: c_uint) -> CuResult {
    if env_number("FAKE_CUDA_DEVICES") == Some(0) {
        return NO_DEVICE;
    }
    with_driver(|_| SUCCESS)
}

/// # Safety
/// `count` must be writable.
#[no_mangle]
pub unsafe extern "C" fn cuDeviceGetCount(count: *mut c_int) -> CuResult {
    *count = env_number("FAKE_CUDA_DEVICES").unwrap_or(1) as c_int;
    SUCCESS
}

/// # Safety
/// `device` must be writable.
#[no_mangle]
pub unsafe extern "C" fn cuDeviceGet(device: *mut c_int, ordinal: c_int) -> CuResult {
    if ordinal < 0 || ordinal as usize >= env_number("FAKE_CUDA_DEVICES").unwrap_or(1) {
        return INVALID_VALUE;
    }
    *device = ordinal;
    SUCCESS
}

/// # Safety
/// `value` must be writable.
#[no_mangle]
pub unsafe extern "C" fn cuDeviceGetAttribute(value: *mut c_int, attribute: c_int, _device: c_int) -> CuResult {
    *value = match attribute {
        attribute::CLOCK_RATE => CLOCK_KHZ,
        attribute::MULTIPROCESSOR_COUNT => MULTIPROCESSORS,
        attribute::COMPUTE_CAPABILITY_MAJOR => (ARCH / 10) as c_int,
        attribute::COMPUTE_CAPABILITY_MINOR => (ARCH % 10) as c_int,
        attribute::MEMORY_POOLS_SUPPORTED => 1,
        _ => 0,
    };
    SUCCESS
}

/// # Safety
/// `name` must hold `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn cuDeviceGetName(name: *mut c_char, len: c_int, _device: c_int) -> CuResult {
    let text = NAME.to_bytes_with_nul();
    let n = text.len().min(len.max(0) as usize);
    std::ptr::copy_nonoverlapping(text.as_ptr().cast(), name, n);
    if n > 0 {
        *name.add(n - 1) = 0;
    }
    SUCCESS
}

/// # Safety
/// `context` must be writable.
#[no_mangle]
pub unsafe extern "C" fn cuDevicePrimaryCtxRetain(context: *mut *mut c_void, _device: c_int) -> CuResult {
    with_driver(|_| {
        *context = 0x1000 as *mut c_void;
        SUCCESS
    })
}

#[no_mangle]
pub extern "C" fn cuDevicePrimaryCtxRelease_v2(_device: c_int) -> CuResult {
    SUCCESS
}

#[no_mangle]
pub extern "C" fn cuCtxDestroy_v2(_context: *mut c_void) -> CuResult {
    SUCCESS
}

/// # Safety
/// `context` must be writable.
#[no_mangle]
pub unsafe extern "C" fn cuCtxGetCurrent(context: *mut *mut c_void) -> CuResult {
    with_driver(|d| {
        *context = d.current_context as *mut c_void;
        SUCCESS
    })
}

#[no_mangle]
pub extern "C" fn cuCtxSetCurrent(context: *mut c_void) -> CuResult {
    with_driver(|d| {
        d.current_context = context as usize;
        SUCCESS
    })
}

/// # Safety
/// `text` must be writable.
#[no_mangle]
pub unsafe extern "C" fn cuGetErrorString(error: CuResult, text: *mut *const c_char) -> CuResult {
    let message: &CStr = match error {
        SUCCESS => c"no error",
        INVALID_VALUE => c"invalid argument",
        OUT_OF_MEMORY => c"out of memory",
        NO_DEVICE => c"no CUDA-capable device is detected",
        INVALID_IMAGE => c"device kernel image is invalid",
        NO_BINARY_FOR_GPU => c"no kernel image is available for execution on the device",
        UNSUPPORTED_PTX_VERSION => c"the provided PTX was compiled with an unsupported toolchain.",
        NOT_FOUND => c"named symbol not found",
        NOT_READY => c"device not ready",
        ILLEGAL_ADDRESS => c"an illegal memory access was encountered",
        NOT_SUPPORTED => c"operation not supported",
        _ => c"unknown error",
    };
    *text = message.as_ptr();
    SUCCESS
}

/// # Safety
/// `free` and `total` must be writable.
#[no_mangle]
pub unsafe extern "C" fn cuMemGetInfo_v2(free: *mut usize, total: *mut usize) -> CuResult {
    with_driver(|d| {
        *total = Driver::total_bytes();
        *free = Driver::total_bytes().saturating_sub(d.used_bytes);
        SUCCESS
    })
}

/// # Safety
/// `address` must be writable.
#[no_mangle]
pub unsafe extern "C" fn cuMemAlloc_v2(address: *mut u64, bytes: usize) -> CuResult {
    with_driver(|d| d.allocate(bytes, address))
}

/// # Safety
/// `address` must be writable.
#[no_mangle]
pub unsafe extern "C" fn cuMemAllocAsync(address: *mut u64, bytes: usize, _stream: *mut c_void) -> CuResult {
    with_driver(|d| d.allocate(bytes, address))
}

#[no_mangle]
pub extern "C" fn cuMemFree_v2(address: u64) -> CuResult {
    with_driver(|d| match d.synchronise() {
        SUCCESS => d.free(address).map_or(INVALID_VALUE, |()| SUCCESS),
        error => error,
    })
}

#[no_mangle]
pub extern "C" fn cuMemFreeAsync(address: u64, _stream: *mut c_void) -> CuResult {
    with_driver(|d| {
        d.queue.push(Op::Free(address));
        SUCCESS
    })
}

/// # Safety
/// `from` must hold `bytes` bytes.
#[no_mangle]
pub unsafe extern "C" fn cuMemcpyHtoDAsync_v2(to: u64, from: *const c_void, bytes: usize, _stream: *mut c_void) -> CuResult {
    let bytes = std::slice::from_raw_parts(from.cast::<u8>(), bytes).to_vec();
    with_driver(|d| {
        d.queue.push(Op::Upload { to, bytes });
        SUCCESS
    })
}

#[no_mangle]
pub extern "C" fn cuMemcpyDtoHAsync_v2(to: *mut c_void, from: u64, bytes: usize, _stream: *mut c_void) -> CuResult {
    with_driver(|d| {
        d.queue.push(Op::Download { to: to as usize, from, bytes });
        SUCCESS
    })
}

#[no_mangle]
pub extern "C" fn cuMemcpyDtoDAsync_v2(to: u64, from: u64, bytes: usize, _stream: *mut c_void) -> CuResult {
    with_driver(|d| {
        d.queue.push(Op::Copy { to, from, bytes });
        SUCCESS
    })
}

#[no_mangle]
pub extern "C" fn cuMemcpyPeerAsync() -> CuResult {
    NOT_SUPPORTED
}

#[no_mangle]
pub extern "C" fn cuMemsetD8Async(to: u64, value: u8, bytes: usize, _stream: *mut c_void) -> CuResult {
    with_driver(|d| {
        d.queue.push(Op::Set { to, value, bytes });
        SUCCESS
    })
}

#[no_mangle]
pub extern "C" fn cuModuleLoad() -> CuResult {
    NOT_SUPPORTED
}

/// # Safety
/// `module` must be writable and `image` PTX text or a fatbin.
#[no_mangle]
pub unsafe extern "C" fn cuModuleLoadData(module: *mut *mut c_void, image: *const c_void) -> CuResult {
    load(module, image, None)
}

/// # Safety
/// As [`cuModuleLoadData`], and `options` and `values` must hold `count` entries each.
#[no_mangle]
pub unsafe extern "C" fn cuModuleLoadDataEx(
    module: *mut *mut c_void,
    image: *const c_void,
    count: c_uint,
    options: *mut c_int,
    values: *mut *mut c_void,
) -> CuResult {
    let (mut buffer, mut size) = (std::ptr::null_mut::<u8>(), 0usize);
    for k in 0..count as usize {
        match *options.add(k) {
            JIT_ERROR_LOG_BUFFER => buffer = (*values.add(k)).cast(),
            // The driver reads the size from the pointer-sized value itself.
            JIT_ERROR_LOG_BUFFER_SIZE_BYTES => size = *values.add(k) as usize,
            _ => {}
        }
    }
    let log = (!buffer.is_null()).then(|| std::slice::from_raw_parts_mut(buffer, size));
    load(module, image, log)
}

#[no_mangle]
pub extern "C" fn cuModuleUnload(module: *mut c_void) -> CuResult {
    if !module.is_null() {
        // SAFETY: a module of `load`, unloaded once.
        drop(unsafe { Box::from_raw(module.cast::<Module>()) });
    }
    SUCCESS
}

/// # Safety
/// `function` must be writable, `module` loaded and `name` a C string.
#[no_mangle]
pub unsafe extern "C" fn cuModuleGetFunction(function: *mut *mut c_void, module: *mut c_void, name: *const c_char) -> CuResult {
    let module = &*module.cast::<Module>();
    let Ok(name) = CStr::from_ptr(name).to_str() else { return NOT_FOUND };
    let (Some(sizes), Some(entry)) = (module.entries.get(name), find_entry(name)) else {
        return NOT_FOUND;
    };
    let kernel = Kernel { name: name.to_string(), entry, param_sizes: sizes.clone() };
    *function = Box::into_raw(Box::new(kernel)).cast();
    SUCCESS
}

/// # Safety
/// `function` must come from [`cuModuleGetFunction`] and `params` hold a pointer to each of
/// its parameters.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn cuLaunchKernel(
    function: *mut c_void,
    grid_x: c_uint,
    grid_y: c_uint,
    grid_z: c_uint,
    block_x: c_uint,
    block_y: c_uint,
    block_z: c_uint,
    shared_bytes: c_uint,
    _stream: *mut c_void,
    params: *mut *mut c_void,
    extra: *mut *mut c_void,
) -> CuResult {
    let kernel: &'static Kernel = &*function.cast::<Kernel>();
    let one_dimensional = grid_y == 1 && grid_z == 1 && block_y == 1 && block_z == 1;
    if !one_dimensional || block_x == 0 || block_x > 1024 || shared_bytes != 0 || !extra.is_null() || params.is_null() {
        return INVALID_VALUE;
    }
    let params = (0..kernel.param_sizes.len())
        .map(|k| std::slice::from_raw_parts((*params.add(k)).cast::<MaybeUninit<u8>>(), kernel.param_sizes[k]).to_vec())
        .collect();
    let threads = grid_x as usize * block_x as usize;
    with_driver(|d| {
        d.launches += 1;
        let faults = env_number("FAKE_CUDA_ILLEGAL_ADDRESS_AT_LAUNCH") == Some(d.launches);
        d.queue.push(Op::Launch { kernel, threads, params, faults });
        SUCCESS
    })
}

/// # Safety
/// `event` must be writable.
#[no_mangle]
pub unsafe extern "C" fn cuEventCreate(event: *mut *mut c_void, _flags: c_uint) -> CuResult {
    with_driver(|d| {
        d.events.push(None);
        // Handles start at 1: a null event is none.
        *event = d.events.len() as *mut c_void;
        SUCCESS
    })
}

#[no_mangle]
pub extern "C" fn cuEventDestroy_v2(_event: *mut c_void) -> CuResult {
    SUCCESS
}

#[no_mangle]
pub extern "C" fn cuEventRecord(event: *mut c_void, _stream: *mut c_void) -> CuResult {
    with_driver(|d| match (event as usize).checked_sub(1).filter(|&e| e < d.events.len()) {
        Some(e) => {
            d.queue.push(Op::Record(e));
            SUCCESS
        }
        None => INVALID_VALUE,
    })
}

#[no_mangle]
pub extern "C" fn cuEventSynchronize(_event: *mut c_void) -> CuResult {
    with_driver(Driver::synchronise)
}

/// # Safety
/// `ms` must be writable.
#[no_mangle]
pub unsafe extern "C" fn cuEventElapsedTime(ms: *mut f32, start: *mut c_void, end: *mut c_void) -> CuResult {
    with_driver(|d| {
        let time = |event: *mut c_void| (event as usize).checked_sub(1).and_then(|e| d.events.get(e).copied().flatten());
        match (time(start), time(end)) {
            (Some(start), Some(end)) => {
                *ms = end.duration_since(start).as_secs_f32() * 1e3;
                SUCCESS
            }
            _ => NOT_READY,
        }
    })
}

#[no_mangle]
pub extern "C" fn cuStreamSynchronize(_stream: *mut c_void) -> CuResult {
    with_driver(Driver::synchronise)
}

#[no_mangle]
pub extern "C" fn cuStreamWaitEvent(_stream: *mut c_void, _event: *mut c_void, _flags: c_uint) -> CuResult {
    with_driver(|_| SUCCESS)
}

#[no_mangle]
pub extern "C" fn cuStreamDestroy_v2(_stream: *mut c_void) -> CuResult {
    SUCCESS
}
