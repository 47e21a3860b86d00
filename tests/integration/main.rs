//! coil's tests, but the CUDA backend's (`tests/cuda.rs`, built with the `cuda` feature): one
//! binary, so that a build links them once.

#[path = "../common/mod.rs"]
mod common;

mod bench;
mod carried_state;
mod hostile_input;
mod inlet_and_time_step;
mod kernels;
mod output;
mod physics;
mod scenes;
mod stability;
mod surface;
mod validation;
