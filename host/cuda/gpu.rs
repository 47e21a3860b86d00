//! The CUDA device of a run: its context and stream, the kernels' PTX module (compiled by
//! build.rs from `kernels/`), launches by kernel name, and allocations with clear errors.

use cudarc::driver::{
    sys, CudaContext, CudaEvent, CudaFunction, CudaModule, CudaSlice, CudaStream, DevicePtr, DeviceRepr, DriverError,
    LaunchConfig, PushKernelArg, ValidAsZeroBits,
};
use cudarc::nvrtc::Ptx;
use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

/// The kernels crate as PTX.
pub const PTX: &str = include_str!(concat!(env!("OUT_DIR"), "/coil_kernels.ptx"));

/// Threads per block of every launch.
const BLOCK: u32 = 256;

/// Why the CUDA backend cannot run.
#[derive(Debug)]
pub enum CudaError {
    /// No CUDA driver library (libcuda) on this machine.
    NoDriver,
    /// The driver loaded but reports no device.
    NoDevice,
    /// A device allocation failed.
    OutOfMemory { what: String, bytes: usize, free: usize, total: usize },
    /// The driver refused the PTX module.
    PtxLoad(DriverError),
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
            CudaError::NoDevice => f.write_str("the CUDA driver reports no device; use --backend cpu"),
            CudaError::OutOfMemory { what, bytes, free, total } => write!(
                f,
                "out of device memory allocating {what}: {bytes} bytes needed, {free} of {total} bytes free; lower the particle count (spacing, max_fluid_particles) or use --precision f32"
            ),
            CudaError::PtxLoad(e) => {
                write!(f, "the CUDA driver could not load coil's PTX ({e}); the driver may be older than the PTX ISA, set COIL_PTX_TARGET_CPU and rebuild")
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
// device pointers), laid out alike on the host and on nvptx64.
unsafe impl<T: Copy> DeviceRepr for ByValue<T> {}

pub struct Gpu {
    ctx: Arc<CudaContext>,
    pub stream: Arc<CudaStream>,
    module: Arc<CudaModule>,
    functions: HashMap<String, CudaFunction>,
    /// Synchronise after every launch, so a failure names its kernel (COIL_CUDA_SYNC=1).
    sync_each_launch: bool,
    last_kernel: &'static str,
    /// While profiling: each launch's kernel and the events recorded around it.
    profile: Option<Vec<(&'static str, CudaEvent, CudaEvent)>>,
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
    /// Opens device 0 and loads the kernels. Checks for the driver library first: cudarc's
    /// loader panics without it.
    pub fn open() -> Result<Self, CudaError> {
        // SAFETY: only tries to open the library.
        if !unsafe { sys::is_culib_present() } {
            return Err(CudaError::NoDriver);
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
        let module = ctx.load_module(Ptx::from_src(PTX)).map_err(CudaError::PtxLoad)?;
        let sync_each_launch = std::env::var("COIL_CUDA_SYNC").is_ok_and(|v| v == "1");
        Ok(Self { ctx, stream, module, functions: HashMap::new(), sync_each_launch, last_kernel: "(none)", profile: None })
    }

    /// The device's name and compute capability, for logs.
    pub fn describe(&self) -> String {
        let name = self.ctx.name().unwrap_or_else(|_| "unknown device".into());
        match self.ctx.compute_capability() {
            Ok((major, minor)) => format!("{name} (sm_{major}{minor})"),
            Err(_) => name,
        }
    }

    /// (free, total) bytes of device memory.
    pub fn memory(&self) -> (usize, usize) {
        self.ctx.mem_get_info().unwrap_or((0, 0))
    }

    /// A zeroed device array of `len` elements; `what` names it in an out-of-memory error.
    pub fn zeros<T: DeviceRepr + ValidAsZeroBits>(&self, len: usize, what: &str) -> Result<CudaSlice<T>, CudaError> {
        // A zero-length allocation is an error in the driver.
        self.stream.alloc_zeros::<T>(len.max(1)).map_err(|error| {
            if error.0 == sys::cudaError_enum::CUDA_ERROR_OUT_OF_MEMORY {
                let (free, total) = self.memory();
                CudaError::OutOfMemory { what: what.into(), bytes: len.max(1) * std::mem::size_of::<T>(), free, total }
            } else {
                CudaError::Driver { call: "cuMemAlloc", error }
            }
        })
    }

    /// Copies `host` into the start of `device`.
    pub fn upload<T: DeviceRepr>(&self, host: &[T], device: &mut CudaSlice<T>) -> Result<(), CudaError> {
        if host.is_empty() {
            return Ok(());
        }
        let mut target = device.slice_mut(..host.len());
        self.stream.memcpy_htod(host, &mut target).map_err(|error| self.failed("cuMemcpyHtoD", error))
    }

    /// Copies the first `host.len()` elements of `device` into `host` (waits for the stream).
    pub fn download<T: DeviceRepr>(&self, device: &CudaSlice<T>, host: &mut [T]) -> Result<(), CudaError> {
        if host.is_empty() {
            return Ok(());
        }
        self.stream.memcpy_dtoh(&device.slice(..host.len()), host).map_err(|error| self.failed("cuMemcpyDtoH", error))
    }

    /// Zeroes `device`.
    pub fn clear<T: DeviceRepr + ValidAsZeroBits>(&self, device: &mut CudaSlice<T>) -> Result<(), CudaError> {
        self.stream.memset_zeros(device).map_err(|error| self.failed("cuMemsetD8", error))
    }

    /// Waits for all queued work.
    pub fn synchronize(&self) -> Result<(), CudaError> {
        self.stream.synchronize().map_err(|error| self.failed("cuStreamSynchronize", error))
    }

    /// A timing event recorded now on the stream.
    pub fn mark(&self) -> Result<CudaEvent, CudaError> {
        self.stream
            .record_event(Some(sys::CUevent_flags::CU_EVENT_DEFAULT))
            .map_err(|error| CudaError::Driver { call: "cuEventRecord", error })
    }

    /// Milliseconds of GPU time between two events from `mark` (waits for `end`).
    pub fn elapsed_ms(&self, start: &CudaEvent, end: &CudaEvent) -> Result<f64, CudaError> {
        start.elapsed_ms(end).map(f64::from).map_err(|error| self.failed("cuEventElapsedTime", error))
    }

    /// Device-to-device copy bandwidth (bytes/s, read plus write): the median of 5 copies of
    /// 256 MiB, or of a quarter of free memory where that is less.
    pub fn copy_bandwidth(&self) -> Result<f64, CudaError> {
        let bytes = (256usize << 20).min(self.memory().0 / 4).max(1 << 20);
        let source = self.zeros::<u8>(bytes, "bandwidth probe")?;
        let mut target = self.zeros::<u8>(bytes, "bandwidth probe")?;
        let mut rates = Vec::new();
        for _ in 0..5 {
            let start = self.mark()?;
            self.stream.memcpy_dtod(&source, &mut target).map_err(|error| self.failed("cuMemcpyDtoD", error))?;
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

    /// The device address of `slice`, for the views inside kernel arguments.
    pub fn address<T>(&self, slice: &CudaSlice<T>) -> u64 {
        let (ptr, _sync) = slice.device_ptr(&self.stream);
        ptr
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
        if !self.functions.contains_key(name) {
            let f = self.module.load_function(name).map_err(|_| CudaError::MissingKernel(name.into()))?;
            self.functions.insert(name.into(), f);
        }
        let f = &self.functions[name];
        let mut builder = self.stream.launch_builder(f);
        for a in args {
            a.push(&mut builder);
        }
        let cfg = LaunchConfig { grid_dim: (threads.div_ceil(BLOCK), 1, 1), block_dim: (BLOCK, 1, 1), shared_mem_bytes: 0 };
        self.last_kernel = name;
        let start = if self.profile.is_some() { Some(self.mark()?) } else { None };
        builder.launch(cfg).map_err(|error| CudaError::Launch { kernel: name.into(), error })?;
        if let Some(start) = start {
            let end = self.mark()?;
            self.profile.get_or_insert_with(Vec::new).push((name, start, end));
        }
        if self.sync_each_launch {
            self.stream.synchronize().map_err(|error| CudaError::Launch { kernel: name.into(), error })?;
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

/// One kernel argument of [`Gpu::launch`].
pub trait Arg {
    fn push<'a>(&'a self, builder: &mut cudarc::driver::LaunchArgs<'a>);
}

impl<T: Copy> Arg for ByValue<T> {
    fn push<'a>(&'a self, builder: &mut cudarc::driver::LaunchArgs<'a>) {
        builder.arg(self);
    }
}
