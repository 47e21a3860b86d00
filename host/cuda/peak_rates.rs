//! What a GPU could do at best: its peak floating-point rates, which `coil bench` compares the
//! kernels' achieved rates with. Known without the backend, so that reports read the same in
//! every build.

use crate::scene::Precision;

/// Peak floating-point rates of a GPU (operations/s, a fused multiply-add counted as two).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakRates {
    pub f32: f64,
    pub f64: f64,
}

impl PeakRates {
    /// From the compute capability, the multiprocessor count and the peak clock (Hz): the
    /// f32 and f64 lanes of a multiprocessor of that architecture, each doing a fused
    /// multiply-add a cycle (CUDA C++ Programming Guide, arithmetic instruction throughput).
    /// None for an architecture not listed.
    pub fn of(compute_capability: (i32, i32), multiprocessors: f64, clock_hz: f64) -> Option<Self> {
        let (f32_lanes, f64_lanes) = match compute_capability {
            (7, 0) | (8, 0) => (64.0, 32.0),
            (7, 5) => (64.0, 2.0),
            (8, 6) | (8, 9) | (12, _) => (128.0, 2.0),
            (9, 0) | (10, 0) => (128.0, 64.0),
            _ => return None,
        };
        let cycle = 2.0 * multiprocessors * clock_hz;
        Some(Self { f32: f32_lanes * cycle, f64: f64_lanes * cycle })
    }

    /// The rate of precision `p`.
    pub fn of_precision(&self, p: Precision) -> f64 {
        match p {
            Precision::F32 => self.f32,
            Precision::F64 => self.f64,
        }
    }
}
