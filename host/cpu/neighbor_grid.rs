//! Sorts particles into their grid on the CPU: hashing, the counting sort and the reorder of
//! every particle field (Algorithm 1, line 3), and the CPU backend's neighbor lists. Also drops
//! particles that left the domain box.

use crate::cpu::parallel::launch;
use crate::simulation::carried_state::{Carried, VisitCarried};
use crate::simulation::cell_sort::{sort_by_cell, SortPasses};
use crate::simulation::particle_array::ParticleArray;
use crate::simulation::particles::{view_mut, Particles};
use crate::simulation::sorted_grid::SortedGrid;
use coil_kernels::cell_grid::{hash_pass, HashArgs, Neighborhood};
use coil_kernels::counting_sort::{
    chunk_total, count_particle, gather, scan_chunk, scan_chunk_in_place, scan_chunk_offsets, scan_levels_len, scatter,
    sort_bucket, sum_chunk, Counters, ScanStep, CPU_SCAN_CHUNK,
};
use coil_kernels::fluid_cells::{holds_fluid_pass, near_fluid_pass, HoldsFluidArgs, NearFluidArgs};
use coil_kernels::neighbor_list::{neighbor_list_pass, ListedNeighborhood, NeighborListArgs, NEIGHBOR_SLOTS};
use coil_kernels::smoothing::SmoothingKernels;
use coil_kernels::topology::{Open, Topology};
use coil_kernels::view::{Vec3View, View, ViewMut};
use coil_kernels::Real;
use std::convert::Infallible;
use std::sync::atomic::{AtomicU32, Ordering};

/// The CPU's arrays for sorting particles into a [`SortedGrid`], and its neighbor lists.
pub struct GridSort {
    cell_key: ParticleArray<u32>,
    counters: Vec<AtomicU32>,
    order: ParticleArray<u32>,
    /// The chunk totals, then the levels of their scan (`counting_sort::scan_levels`).
    chunk_offsets: Vec<u32>,
    /// Per cell, whether it holds fluid, where the grid tracks fluid (`fluid_cells`).
    holds_fluid: Vec<u8>,
    /// `NEIGHBOR_SLOTS` per particle of capacity once `keep_neighbor_lists` allocates them.
    neighbor_list: ParticleArray<u32>,
}

impl GridSort {
    /// The arrays to sort up to `capacity` particles into `cells`.
    pub fn new(cells: &SortedGrid, capacity: usize) -> Self {
        let buckets = cells.buckets();
        Self {
            cell_key: ParticleArray::zeros(capacity),
            counters: (0..buckets).map(|_| AtomicU32::new(0)).collect(),
            order: ParticleArray::zeros(capacity),
            chunk_offsets: vec![0; scan_levels_len(buckets.div_ceil(CPU_SCAN_CHUNK))],
            holds_fluid: if cells.tracks_fluid().is_some() { vec![0; buckets - 1] } else { Vec::new() },
            neighbor_list: ParticleArray::default(),
        }
    }

    /// Allocates the neighbor lists (`coil_kernels::neighbor_list`) for every particle of
    /// capacity, so that `record_neighbors` can fill them.
    pub fn keep_neighbor_lists(&mut self) {
        self.neighbor_list = ParticleArray::zeros(self.order.len() * NEIGHBOR_SLOTS);
    }

    /// Whether the sort keeps neighbor lists.
    pub fn keeps_neighbor_lists(&self) -> bool {
        !self.neighbor_list.is_empty()
    }

    /// Records the neighbors within `kernels.h` of the particles at `position`, sorted into
    /// `cells`, in topology `topology`, when the sort keeps lists, and each listed pair's spiky
    /// gradient into `spiky_gradient` where it is not empty (`NEIGHBOR_SLOTS` per particle).
    pub fn record_neighbors<R: Real, T: Topology>(
        &mut self,
        cells: &SortedGrid,
        position: Vec3View<f64>,
        kernels: SmoothingKernels<R>,
        spiky_gradient: &mut [[R; 3]],
        topology: T,
    ) {
        if !self.keeps_neighbor_lists() {
            return;
        }
        let n = position.x.len();
        let gradients = if spiky_gradient.is_empty() { 0 } else { n * NEIGHBOR_SLOTS };
        let args = NeighborListArgs {
            neighborhood: cells.neighborhood(position, topology),
            kernels,
            list: view_mut(&mut self.neighbor_list, n * NEIGHBOR_SLOTS),
            spiky_gradient: view_mut(spiky_gradient, gradients),
        };
        launch(n, |i| neighbor_list_pass(i, &args));
    }

    /// The neighbors of the particles at `position` as the last `record_neighbors` over these
    /// positions found them, with the gradients it recorded with `kernels`, for a sort that
    /// keeps lists.
    pub fn listed_neighborhood<'a, R: Real, T: Topology>(
        &'a self,
        cells: &'a SortedGrid,
        position: Vec3View<'a, f64>,
        topology: T,
        kernels: SmoothingKernels<R>,
        spiky_gradient: &'a [[R; 3]],
    ) -> ListedNeighborhood<'a, T, R> {
        ListedNeighborhood {
            grid: cells.neighborhood(position, topology),
            list: View::new(&self.neighbor_list),
            kernels,
            spiky_gradient: View::new(spiky_gradient),
        }
    }

    /// Bytes of the sort's own arrays.
    pub fn bytes(&self) -> usize {
        4 * (self.cell_key.len() + self.counters.len() + self.order.len() + self.chunk_offsets.len() + self.neighbor_list.len())
            + self.holds_fluid.len()
    }

    /// Sorts the particles into `cells` (`cell_sort`), dropping those outside the domain;
    /// returns how many left.
    pub fn sort<R: Real>(&mut self, cells: &mut SortedGrid, p: &mut Particles<R>) -> usize {
        let n = p.len();
        let Ok(()) = sort_by_cell(&mut CpuCellSort { sort: self, cells, p, n });
        n - p.len()
    }

    /// The `fluid_cells` passes over the sorted particles' ids, when the grid tracks fluid.
    fn mark_cells_near_fluid(&mut self, cells: &mut SortedGrid, id: View<u32>) {
        let Some(boundary_count) = cells.tracks_fluid() else {
            return;
        };
        let (grid, periodic, topology) = (cells.grid, cells.is_periodic(), cells.periodic);
        let (cell_start, near_fluid) = cells.starts_and_marks();
        let count = self.holds_fluid.len();
        let args = HoldsFluidArgs { cell_start, id, boundary_count, holds_fluid: ViewMut::new(&mut self.holds_fluid) };
        launch(count, |c| holds_fluid_pass(c, &args));
        let (holds_fluid, near_fluid) = (View::new(&self.holds_fluid), ViewMut::new(near_fluid));
        if periodic {
            let args = NearFluidArgs { grid, topology, cell_start, holds_fluid, near_fluid };
            launch(count, |c| near_fluid_pass(c, &args));
        } else {
            let args = NearFluidArgs { grid, topology: Open, cell_start, holds_fluid, near_fluid };
            launch(count, |c| near_fluid_pass(c, &args));
        }
    }
}

/// The CPU's sort passes: each over its particles, buckets or chunks with rayon, chunks of
/// `CPU_SCAN_CHUNK` buckets.
struct CpuCellSort<'a, R> {
    sort: &'a mut GridSort,
    cells: &'a mut SortedGrid,
    p: &'a mut Particles<R>,
    /// Particles before the sort.
    n: usize,
}

impl<R: Real> SortPasses for CpuCellSort<'_, R> {
    type Fault = Infallible;

    fn chunks(&self) -> usize {
        self.sort.counters.len().div_ceil(CPU_SCAN_CHUNK)
    }

    fn hash(&mut self) -> Result<(), Infallible> {
        let n = self.n;
        let args =
            HashArgs { grid: self.cells.grid, position: self.p.position_view(), cell_key: view_mut(&mut self.sort.cell_key, n) };
        launch(n, |i| hash_pass(i, &args));
        Ok(())
    }

    fn clear_counters(&mut self) -> Result<(), Infallible> {
        let counters = &self.sort.counters;
        launch(counters.len(), |k| counters[k].store(0, Ordering::Relaxed));
        Ok(())
    }

    fn count_particles(&mut self) -> Result<(), Infallible> {
        let (counters, keys) = (Counters::new(&self.sort.counters), View::new(&self.sort.cell_key[..self.n]));
        launch(self.n, |i| count_particle(i, keys, counters));
        Ok(())
    }

    fn chunk_totals(&mut self) -> Result<(), Infallible> {
        let chunks = self.chunks();
        let counters = Counters::new(&self.sort.counters);
        let totals = ViewMut::new(&mut self.sort.chunk_offsets[..chunks]);
        // SAFETY: invocation c writes only entry c.
        launch(chunks, |c| unsafe { totals.write(c, chunk_total(c, CPU_SCAN_CHUNK, counters)) });
        Ok(())
    }

    fn scan_step(&mut self, step: ScanStep) -> Result<(), Infallible> {
        let levels = ViewMut::new(&mut self.sort.chunk_offsets);
        let level = |(start, len): (usize, usize)| levels.range(start, len);
        match step {
            ScanStep::Up { values, sums } => {
                let (values, sums) = (level(values).read(), level(sums));
                // SAFETY: invocation c writes only entry c.
                launch(sums.len(), |c| unsafe { sums.write(c, sum_chunk(c, values)) });
            }
            ScanStep::Top(top) => scan_chunk_offsets(level(top)),
            ScanStep::Down { values, offsets } => {
                let (values, offsets) = (level(values), level(offsets).read());
                launch(offsets.len(), |c| scan_chunk_in_place(c, offsets.at(c), values));
            }
        }
        Ok(())
    }

    fn scan_chunks(&mut self) -> Result<(), Infallible> {
        let chunks = self.chunks();
        let (counters, offsets) = (Counters::new(&self.sort.counters), View::new(&self.sort.chunk_offsets[..chunks]));
        let starts = ViewMut::new(self.cells.cell_start_mut());
        launch(chunks, |c| scan_chunk(c, CPU_SCAN_CHUNK, offsets.at(c), counters, starts));
        Ok(())
    }

    fn scatter_and_sort_buckets(&mut self) -> Result<(), Infallible> {
        let n = self.n;
        let (counters, keys) = (Counters::new(&self.sort.counters), View::new(&self.sort.cell_key[..n]));
        let order = view_mut(&mut self.sort.order, n);
        launch(n, |i| scatter(i, keys, counters, order));
        let starts = View::new(self.cells.cell_start());
        launch(self.cells.grid.cell_count() as usize, |c| sort_bucket(c, starts, order));
        Ok(())
    }

    fn reorder(&mut self) -> Result<(), Infallible> {
        let live = self.cells.live();
        reorder(self.p, View::new(&self.sort.order[..live]), live);
        Ok(())
    }

    fn mark_cells_near_fluid(&mut self) -> Result<(), Infallible> {
        let live = self.p.len();
        self.sort.mark_cells_near_fluid(self.cells, View::new(&self.p.id[..live]));
        Ok(())
    }
}

/// A sorted grid with the CPU's sort: kernels run by hand over particles that no backend
/// holds (tests, checks).
pub struct NeighborGrid {
    pub cells: SortedGrid,
    pub sort: GridSort,
}

impl NeighborGrid {
    /// See [`SortedGrid::new`]; room for `capacity` particles.
    pub fn new(min: [f64; 3], max: [f64; 3], cell_size: f64, periodic: [bool; 3], capacity: usize) -> Self {
        let cells = SortedGrid::new(min, max, cell_size, periodic);
        let sort = GridSort::new(&cells, capacity);
        Self { cells, sort }
    }

    /// See [`SortedGrid::track_fluid`].
    pub fn track_fluid(&mut self, boundary_count: u32) {
        self.cells.track_fluid(boundary_count);
        self.sort = GridSort::new(&self.cells, self.sort.order.len());
    }

    /// Sorts the particles by cell, dropping those outside the domain; returns how many left.
    pub fn sort<R: Real>(&mut self, p: &mut Particles<R>) -> usize {
        self.sort.sort(&mut self.cells, p)
    }

    /// The sorted grid for the particles' current order, in topology `topology`.
    pub fn neighborhood<'a, T: Topology>(&'a self, position: Vec3View<'a, f64>, topology: T) -> Neighborhood<'a, T> {
        self.cells.neighborhood(position, topology)
    }
}

/// Permutes every array that carries state from step to step (`carried_state`) into sorted
/// order; arrays recomputed each step are left alone.
fn reorder<R: Real>(p: &mut Particles<R>, order: View<u32>, live: usize) {
    let density_rate = p.density_is_state();
    let mut permute =
        Permute { order, live, density_rate, wide: &mut p.scratch_f64, real: &mut p.scratch_real, index: &mut p.scratch_u32 };
    crate::visit_carried!(mut &mut permute; p);
    p.set_len(live);
}

/// Gathers each carried array into sorted order through a scratch array of its type, then
/// swaps the two.
struct Permute<'s, R> {
    order: View<'s, u32>,
    live: usize,
    density_rate: bool,
    wide: &'s mut ParticleArray<f64>,
    real: &'s mut ParticleArray<R>,
    index: &'s mut ParticleArray<u32>,
}

fn permute<T: Copy + Send + Sync>(
    fields: &mut [ParticleArray<T>],
    scratch: &mut ParticleArray<T>,
    order: View<u32>,
    live: usize,
) {
    for field in fields {
        let unsorted = View::new(&field[..]);
        let sorted = view_mut(scratch, live);
        launch(live, |k| gather(k, order, unsorted, sorted));
        std::mem::swap(field, scratch);
    }
}

impl<'a, R: Real> VisitCarried<&'a mut [ParticleArray<f64>], &'a mut [ParticleArray<R>], &'a mut [ParticleArray<u32>]>
    for Permute<'_, R>
{
    fn wide(&mut self, array: Carried, components: &'a mut [ParticleArray<f64>]) {
        if array.is_state(self.density_rate) {
            permute(components, self.wide, self.order, self.live);
        }
    }
    fn real(&mut self, array: Carried, components: &'a mut [ParticleArray<R>]) {
        if array.is_state(self.density_rate) {
            permute(components, self.real, self.order, self.live);
        }
    }
    fn index(&mut self, array: Carried, components: &'a mut [ParticleArray<u32>]) {
        if array.is_state(self.density_rate) {
            permute(components, self.index, self.order, self.live);
        }
    }
}
