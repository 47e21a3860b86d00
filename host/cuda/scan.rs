//! The exclusive scan of the sort's chunk totals on the device, level by level
//! (`coil_kernels::counting_sort::scan_levels`): no thread walks more than `SCAN_FAN_IN` entries
//! in series, however fine the grid.

use super::device_array::DeviceArray;
use super::gpu::{Arg, ByValue, CudaError, Gpu};
use coil_kernels::counting_sort::{scan_by_levels, scan_levels_len, ScanStep};

/// Scans the first `totals` entries of `levels` in place (exclusive), with the rest of it, at
/// least `scan_levels_len(totals)` entries in all, for the levels above.
pub fn scan_chunk_totals(gpu: &mut Gpu, levels: &DeviceArray<u32>, totals: usize) -> Result<(), CudaError> {
    assert!(levels.len() >= scan_levels_len(totals), "too few entries for the scan's levels");
    scan_by_levels(totals, |step| scan_step(gpu, levels, step))
}

/// One step of the scan of chunk totals in `levels` (`scan_by_levels`).
pub fn scan_step(gpu: &mut Gpu, levels: &DeviceArray<u32>, step: ScanStep) -> Result<(), CudaError> {
    let launch = |gpu: &mut Gpu, kernel: &'static str, threads: usize, args: &[&dyn Arg]| {
        // SAFETY: each argument list is its entry's in `coil_kernels::ptx`, every view within
        // `levels`.
        unsafe { gpu.launch(kernel, threads as u32, args) }
    };
    match step {
        ScanStep::Up { values: (values, values_len), sums: (sums, len) } => {
            let (values, sums) = (levels.view_range(values, values_len), levels.view_mut_range(sums, len));
            launch(gpu, "scan_sum_chunks", len, &[&ByValue(len as u32), &ByValue(values), &ByValue(sums)])
        }
        ScanStep::Top((top, len)) => launch(gpu, "scan_offsets", 1, &[&ByValue(levels.view_mut_range(top, len))]),
        ScanStep::Down { values: (values, values_len), offsets: (offsets, len) } => {
            let (values, offsets) = (levels.view_mut_range(values, values_len), levels.view_range(offsets, len));
            launch(gpu, "scan_chunks_in_place", len, &[&ByValue(len as u32), &ByValue(offsets), &ByValue(values)])
        }
    }
}
