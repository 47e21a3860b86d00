#![allow(clippy::neg_cmp_op_on_partial_ord, reason = "`!(a < b)` is how a check here also refuses NaN")]
pub use coil_kernels as kernels;
pub mod bench;
pub mod bench_report;
pub mod check;
#[cfg(feature = "cuda")]
pub mod cuda;
pub mod frame;
pub mod image;
pub mod inlet;
pub mod model;
pub mod neighbor_grid;
pub mod operation_count;
pub mod output;
pub mod parallel;
pub mod particles;
pub mod plot;
pub mod preview;
pub mod run;
pub mod run_log;
pub mod scene;
pub mod scene_override;
pub mod setup;
pub mod simulation;
pub mod statistics;
pub mod time_step;
pub mod toml_field;
pub mod validation;
