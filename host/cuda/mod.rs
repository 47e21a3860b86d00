//! The CUDA backend: the kernels of `kernels/` as PTX (built by build.rs), run on an NVIDIA GPU
//! through cudarc, which loads the driver at run time so that a `cuda` build starts anywhere.

pub mod device_array;
pub mod gpu;
pub mod gpu_simulation;
pub mod scan;

pub use gpu::{CudaError, Gpu, KernelTime};
pub use gpu_simulation::{CudaBackend, GpuSimulation, GpuStepError};
