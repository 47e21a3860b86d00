//! The kernels as the driver receives them: the PTX that build.rs compiled from `kernels/`,
//! and a fatbin of cubins where the build had `ptxas`; how they load, and what the driver must
//! offer.

use crate::cuda::error::CudaError;
use cudarc::driver::{sys, CudaContext, CudaModule, DriverError};
use cudarc::nvrtc::Ptx;
use std::sync::Arc;

/// The kernels crate as PTX.
pub const PTX: &str = include_str!(concat!(env!("OUT_DIR"), "/coil_kernels.ptx"));

/// The kernels compiled ahead of time: a fatbin of cubins for [`CUBIN_ARCHS`] and the PTX, which
/// the driver loads without compiling on those GPUs; empty where the build found no `ptxas`.
pub const FATBIN: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/coil_kernels.fatbin"));

/// The architectures of [`FATBIN`]'s cubins, as `sm_XY` numbers (`80,90`); empty without one.
pub const CUBIN_ARCHS: &str = env!("COIL_CUBIN_ARCHS");

/// The driver functions coil's calls reach through cudarc. cudarc looks each up at its first call
/// and panics where the driver lacks it, so [`Gpu::open`](crate::cuda::gpu::Gpu::open) looks them all up first: a driver too
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
pub(crate) fn missing_driver_function() -> Option<&'static str> {
    // SAFETY: only called once `is_culib_present` found the library; looks symbols up, calls none.
    let library = unsafe { sys::culib() };
    DRIVER_FUNCTIONS.iter().copied().find(|name| unsafe { library.get::<*const std::ffi::c_void>(name.as_bytes()) }.is_err())
}

/// What the driver's JIT compiler says when it refuses `ptx`, the context current: cudarc's load
/// passes no log buffer, so a refused module is loaded once more with one. `None` where the load
/// succeeds or the log is empty.
pub(crate) fn jit_error_log(ptx: &str) -> Option<String> {
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

/// How the kernels reached the device.
pub(crate) enum KernelCode {
    /// [`FATBIN`]: a cubin where one fits the device, the PTX JIT-compiled where none does.
    Fatbin,
    /// [`PTX`] alone, JIT-compiled by the driver: the build had no `ptxas`, or the driver refused
    /// the fatbin (one older than the `ptxas` that compiled it).
    Ptx { fatbin_refused: Option<DriverError> },
}

/// Loads the kernels: [`FATBIN`] where the build made one and the driver takes it, else [`PTX`].
pub(crate) fn load_kernels(ctx: &Arc<CudaContext>) -> Result<(Arc<CudaModule>, KernelCode), CudaError> {
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
pub(crate) fn cubin_for(major: i32, minor: i32) -> Option<u32> {
    let device = (major * 10 + minor) as u32;
    CUBIN_ARCHS.split(',').filter_map(|a| a.parse::<u32>().ok()).filter(|&a| a / 10 == device / 10 && a <= device).max()
}
