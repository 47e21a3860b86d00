//! The device's sort passes (`simulation::cell_sort`): each a launch of its PTX entry over the
//! device's arrays, in chunks of `DEVICE_SCAN_CHUNK` buckets. Nothing waits for the device: the
//! passes read the live count from device memory, and the sort leaves the new count there.

use super::device_array::vec3_view;
use super::device_carried::reorder_carried;
use super::device_state::{buckets_chunks, DeviceState};
use super::gpu::{Arg, ByValue, CudaError, Gpu};
use super::scan::scan_step;
use crate::simulation::cell_sort::SortPasses;
use crate::simulation::sorted_grid::SortedGrid;
use coil_kernels::cell_grid::HashArgs;
use coil_kernels::counting_sort::{ScanStep, DEVICE_SCAN_CHUNK};
use coil_kernels::fluid_cells::{HoldsFluidArgs, NearFluidArgs};
use coil_kernels::topology::{Open, Topology};
use coil_kernels::view::View;
use coil_kernels::Real;

/// The device's sort of its `bound` particles (an upper bound on the live count) into `grid`.
pub(super) struct DeviceCellSort<'a, R> {
    pub(super) gpu: &'a mut Gpu,
    pub(super) d: &'a mut DeviceState<R>,
    /// The grid's shape, periods and whether it tracks fluid, as the host keeps them.
    pub(super) grid: &'a SortedGrid,
    pub(super) bound: usize,
}

impl<R: Real> DeviceCellSort<'_, R> {
    fn count(&self) -> ByValue<View<'static, u32>> {
        ByValue(self.d.count.view(1))
    }

    /// Launches `kernel` on `threads` threads.
    fn launch(&mut self, kernel: &'static str, threads: usize, args: &[&dyn Arg]) -> Result<(), CudaError> {
        // SAFETY: each argument list is its entry's in `coil_kernels::ptx`, over arrays sized to
        // the capacity (particles) or to the grid (buckets, chunks, cells).
        unsafe { self.gpu.launch(kernel, threads as u32, args) }
    }

    /// The `fluid_cells` passes in `topology`.
    fn mark<T: Topology>(&mut self, topology: T, boundary_count: u32) -> Result<(), CudaError> {
        let d = &self.d;
        let Some(holds_fluid) = &d.holds_fluid else { return Ok(()) };
        let grid = self.grid.grid;
        let cells = grid.cell_count() as usize;
        let cell_start = d.cell_start.view(d.cell_start.len());
        let holds =
            HoldsFluidArgs { cell_start, id: d.id.view(self.bound), boundary_count, holds_fluid: holds_fluid.view_mut(cells) };
        let near = NearFluidArgs {
            grid,
            topology,
            cell_start,
            holds_fluid: holds_fluid.view(cells),
            near_fluid: d.near_fluid.view_mut(cells),
        };
        let cells_arg = ByValue(cells as u32);
        self.launch("holds_fluid", cells, &[&cells_arg, &ByValue(holds)])?;
        let near_fluid = if T::PERIODIC { "near_fluid_periodic" } else { "near_fluid" };
        self.launch(near_fluid, cells, &[&cells_arg, &ByValue(near)])
    }
}

impl<R: Real> SortPasses for DeviceCellSort<'_, R> {
    type Fault = CudaError;

    fn chunks(&self) -> usize {
        buckets_chunks(self.d.counters.len())
    }

    fn hash(&mut self) -> Result<(), CudaError> {
        let n = self.bound;
        let hash =
            HashArgs { grid: self.grid.grid, position: vec3_view(&self.d.position, n), cell_key: self.d.cell_key.view_mut(n) };
        let count = self.count();
        self.launch("hash", n, &[&count, &ByValue(hash)])
    }

    fn clear_counters(&mut self) -> Result<(), CudaError> {
        self.d.counters.clear(self.gpu)
    }

    fn count_particles(&mut self) -> Result<(), CudaError> {
        let n = self.bound;
        let (count, keys, counters) = (self.count(), ByValue(self.d.cell_key.view(n)), ByValue(self.d.counters.counters()));
        self.launch("count_particles", n, &[&count, &keys, &counters])
    }

    fn chunk_totals(&mut self) -> Result<(), CudaError> {
        let chunks = self.chunks();
        let totals = ByValue(self.d.chunk_offsets.view_mut(chunks));
        let args = [ByValue(chunks as u32), ByValue(DEVICE_SCAN_CHUNK as u32)];
        let counters = ByValue(self.d.counters.counters());
        self.launch("scan_chunk_totals", chunks, &[&args[0], &args[1], &counters, &totals])
    }

    fn scan_step(&mut self, step: ScanStep) -> Result<(), CudaError> {
        scan_step(self.gpu, &self.d.chunk_offsets, step)
    }

    fn scan_chunks(&mut self) -> Result<(), CudaError> {
        let chunks = self.chunks();
        let buckets = self.d.counters.len();
        let args = [ByValue(chunks as u32), ByValue(DEVICE_SCAN_CHUNK as u32)];
        let offsets = ByValue(self.d.chunk_offsets.view(chunks));
        let counters = ByValue(self.d.counters.counters());
        let starts = ByValue(self.d.cell_start.view_mut(buckets + 1));
        self.launch("scan_chunks", chunks, &[&args[0], &args[1], &offsets, &counters, &starts])
    }

    fn scatter_and_sort_buckets(&mut self) -> Result<(), CudaError> {
        let n = self.bound;
        let buckets = self.d.counters.len();
        let cells = self.grid.grid.cell_count();
        let (count, keys, counters) = (self.count(), ByValue(self.d.cell_key.view(n)), ByValue(self.d.counters.counters()));
        let order = ByValue(self.d.order.view_mut(n));
        self.launch("scatter_particles", n, &[&count, &keys, &counters, &order])?;
        let starts = ByValue(self.d.cell_start.view(buckets + 1));
        self.launch("sort_buckets", cells as usize, &[&ByValue(cells), &starts, &order])
    }

    fn reorder(&mut self) -> Result<(), CudaError> {
        let n = self.bound;
        let buckets = self.d.counters.len();
        let cells = ByValue(self.grid.grid.cell_count());
        let (count, starts) = (ByValue(self.d.count.view_mut(1)), ByValue(self.d.cell_start.view(buckets + 1)));
        self.launch("set_count", 1, &[&count, &starts, &cells])?;
        let order = self.d.order.view(n);
        reorder_carried(self.gpu, self.d, order, n)
    }

    /// Where the grid does not track fluid, the host's marks (every cell near fluid) stay as
    /// uploaded.
    fn mark_cells_near_fluid(&mut self) -> Result<(), CudaError> {
        let Some(boundary_count) = self.grid.tracks_fluid() else { return Ok(()) };
        match self.grid.is_periodic() {
            true => self.mark(self.grid.periodic, boundary_count),
            false => self.mark(Open, boundary_count),
        }
    }
}
