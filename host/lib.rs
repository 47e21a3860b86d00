pub use coil_kernels as kernels;
