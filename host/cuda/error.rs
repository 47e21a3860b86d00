//! Why the CUDA backend cannot run, in words a user can act on.

use cudarc::driver::DriverError;
use std::fmt;

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
