//! The CUDA backend: the kernels of `kernels/` as PTX (built by build.rs), run on an NVIDIA GPU
//! through cudarc, which loads the driver at run time so that a `cuda` build starts anywhere.
//! Only the GPU's peak rates are in a build without the `cuda` feature.

#[cfg(feature = "cuda")]
pub mod device_array;
#[cfg(feature = "cuda")]
mod device_carried;
#[cfg(feature = "cuda")]
mod device_cell_sort;
#[cfg(feature = "cuda")]
mod device_state;
#[cfg(feature = "cuda")]
mod emulator;
#[cfg(feature = "cuda")]
pub mod error;
#[cfg(feature = "cuda")]
pub mod gpu;
#[cfg(feature = "cuda")]
mod gpu_passes;
#[cfg(feature = "cuda")]
pub mod gpu_simulation;
#[cfg(feature = "cuda")]
pub mod kernel_module;
pub mod peak_rates;
#[cfg(feature = "cuda")]
pub mod scan;

#[cfg(feature = "cuda")]
pub use gpu::{CudaError, Gpu, KernelTime};
#[cfg(feature = "cuda")]
pub use gpu_simulation::{CudaBackend, GpuSimulation, GpuStepError};
