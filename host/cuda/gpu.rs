//! The CUDA device of a run: its context and stream, the kernels' PTX module (compiled by
//! build.rs from `kernels/`), launches by kernel name, and allocations with clear errors.
//!
//! [`Gpu::emulated`] stands in for a device where there is none: its memory is host memory and
//! a launch runs the kernels' host builds (`coil_kernels::ptx::find_entry`) over every thread of
//! the grid with rayon, so the backend's host side runs and is tested without a GPU. As a
//! device's stream does, it runs launches later than they are queued: at the next copy,
//! synchronisation or timing mark.

use crate::cuda::emulator::{lock, Emulator, HostMemory, QueuedLaunch, BLOCK};
pub use crate::cuda::error::CudaError;
use crate::cuda::kernel_module::{cubin_for, load_kernels, missing_driver_function, KernelCode};
pub use crate::cuda::kernel_module::{CUBIN_ARCHS, DRIVER_FUNCTIONS, FATBIN, PTX};
use coil_kernels::ptx::{find_entry, Emulated};
use cudarc::driver::{
    sys, CudaContext, CudaEvent, CudaFunction, CudaModule, CudaSlice, CudaStream, DevicePtr, DeviceRepr, DriverError,
    LaunchConfig, PushKernelArg,
};
use std::collections::HashMap;
use std::mem::MaybeUninit;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Instant;

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

/// What runs the kernels.
enum Engine {
    Cuda(Device),
    /// The kernels' host builds, over host memory.
    Emulated(Emulator),
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
                let entry: Emulated = find_entry(name).ok_or_else(|| CudaError::MissingKernel(name.into()))?;
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
