#![allow(clippy::neg_cmp_op_on_partial_ord, reason = "`!(a < b)` is how a check here also refuses NaN")]
pub use coil_kernels as kernels;
pub mod bench;
pub mod check;
pub mod cpu;
pub mod cuda;
pub mod fnv1a;
pub mod output;
pub mod regular_file;
pub mod run;
pub mod scene;
pub mod simulation;
pub mod splitmix64;
pub mod statistics;
pub mod time_step;
pub mod validation;
