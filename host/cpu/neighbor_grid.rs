//! Drives the neighbor grid on the CPU: hashing, the counting sort and the reorder of every
//! particle field (Algorithm 1, line 3), and the CPU backend's neighbor lists. Also drops
//! particles that left the domain box.

use crate::cpu::parallel::launch;
use crate::simulation::particle_array::ParticleArray;
use crate::simulation::particles::{view_mut, Particles};
use coil_kernels::cell_grid::{hash_pass, CellGrid, HashArgs, Neighborhood};
use coil_kernels::counting_sort::{
    chunk_total, count_particle, gather, scan_by_levels, scan_chunk, scan_chunk_in_place, scan_chunk_offsets, scan_levels_len,
    scatter, sort_bucket, sum_chunk, Counters, ScanStep,
};
use coil_kernels::fluid_cells::{holds_fluid_pass, near_fluid_pass, HoldsFluidArgs, NearFluidArgs};
use coil_kernels::neighbor_list::{neighbor_list_pass, ListedNeighborhood, NeighborListArgs, NEIGHBOR_SLOTS};
use coil_kernels::smoothing::SmoothingKernels;
use coil_kernels::topology::{Open, Periodic, Topology, PERIODIC_ROUNDING};
use coil_kernels::view::{Vec3View, View, ViewMut};
use coil_kernels::Real;
use std::sync::atomic::{AtomicU32, Ordering};

/// Buckets per scan chunk.
pub const SCAN_CHUNK: usize = 4096;

pub struct NeighborGrid {
    pub grid: CellGrid,
    /// The domain's periods (0 along open axes; all 0 for an open domain).
    pub periodic: Periodic,
    cell_key: ParticleArray<u32>,
    counters: Vec<AtomicU32>,
    cell_start: Vec<u32>,
    order: ParticleArray<u32>,
    /// The chunk totals, then the levels of their scan (`counting_sort::scan_levels`).
    chunk_offsets: Vec<u32>,
    /// Per cell: whether it holds fluid (allocated by `track_fluid`), then whether it lies near
    /// fluid (`fluid_cells`).
    holds_fluid: Vec<u8>,
    near_fluid: Vec<u8>,
    /// Ids below this are fixed boundary particles at rest, whose cells each sort marks; `None`
    /// marks every cell near fluid.
    resting_boundary: Option<u32>,
    /// `NEIGHBOR_SLOTS` per particle of capacity once `keep_neighbor_lists` allocates them.
    neighbor_list: ParticleArray<u32>,
}

impl NeighborGrid {
    /// A grid of cells of edge `cell_size` (m, the support radius) over the domain box; along
    /// the axes marked `periodic` the box length is split into whole cells of at least that edge,
    /// less `PERIODIC_ROUNDING` of it.
    pub fn new(min: [f64; 3], max: [f64; 3], cell_size: f64, periodic: [bool; 3], capacity: usize) -> Self {
        let length = [0, 1, 2].map(|a| max[a] - min[a]);
        let dims = [0, 1, 2].map(|a| {
            let cells = length[a] / cell_size;
            (if periodic[a] { (cells * (1.0 + PERIODIC_ROUNDING)).floor() } else { cells.ceil() } as u32).max(1)
        });
        let inverse_cell_size = [0, 1, 2].map(|a| if periodic[a] { dims[a] as f64 / length[a] } else { 1.0 / cell_size });
        let grid = CellGrid { origin: min, inverse_cell_size, dims };
        let periodic = Periodic { origin: min, period: [0, 1, 2].map(|a| if periodic[a] { length[a] } else { 0.0 }) };
        let buckets = grid.cell_count() as usize + 1;
        Self {
            grid,
            periodic,
            cell_key: ParticleArray::zeros(capacity),
            counters: (0..buckets).map(|_| AtomicU32::new(0)).collect(),
            cell_start: vec![0; buckets + 1],
            order: ParticleArray::zeros(capacity),
            chunk_offsets: vec![0; scan_levels_len(buckets.div_ceil(SCAN_CHUNK))],
            holds_fluid: Vec::new(),
            near_fluid: vec![1; buckets - 1],
            resting_boundary: None,
            neighbor_list: ParticleArray::default(),
        }
    }

    /// From the next sort on, marks the cells near fluid, for particles whose ids below
    /// `boundary_count` are fixed boundary particles that stay at rest (not mirrored walls).
    pub fn track_fluid(&mut self, boundary_count: u32) {
        self.resting_boundary = Some(boundary_count);
        self.holds_fluid = vec![0; self.near_fluid.len()];
    }

    /// The boundary count the sorts mark the cells near fluid by; `None` where every cell
    /// counts as near fluid.
    pub fn tracks_fluid(&self) -> Option<u32> {
        self.resting_boundary
    }

    /// Allocates the neighbor lists (`coil_kernels::neighbor_list`) for every particle of
    /// capacity, so that `record_neighbors` can fill them: on the CPU backend only.
    pub fn keep_neighbor_lists(&mut self) {
        self.neighbor_list = ParticleArray::zeros(self.order.len() * NEIGHBOR_SLOTS);
    }

    /// Whether the grid keeps neighbor lists.
    pub fn keeps_neighbor_lists(&self) -> bool {
        !self.neighbor_list.is_empty()
    }

    /// Records the neighbors within `kernels.h` of the sorted particles at `position`, in
    /// topology `topology`, when the grid keeps lists, and each listed pair's spiky gradient
    /// into `spiky_gradient` where it is not empty (`NEIGHBOR_SLOTS` per particle).
    pub fn record_neighbors<R: Real, T: Topology>(
        &mut self,
        position: Vec3View<f64>,
        kernels: SmoothingKernels<R>,
        spiky_gradient: &mut [[R; 3]],
        topology: T,
    ) {
        if !self.keeps_neighbor_lists() {
            return;
        }
        let n = position.x.len();
        let mut list = std::mem::take(&mut self.neighbor_list);
        let gradients = if spiky_gradient.is_empty() { 0 } else { n * NEIGHBOR_SLOTS };
        let args = NeighborListArgs {
            neighborhood: self.neighborhood(position, topology),
            kernels,
            list: view_mut(&mut list, n * NEIGHBOR_SLOTS),
            spiky_gradient: view_mut(spiky_gradient, gradients),
        };
        launch(n, |i| neighbor_list_pass(i, &args));
        self.neighbor_list = list;
    }

    /// The neighbors of the particles at `position` as the last `record_neighbors` over these
    /// positions found them, with the gradients it recorded with `kernels`, for a grid that
    /// keeps lists.
    pub fn listed_neighborhood<'a, R: Real, T: Topology>(
        &'a self,
        position: Vec3View<'a, f64>,
        topology: T,
        kernels: SmoothingKernels<R>,
        spiky_gradient: &'a [[R; 3]],
    ) -> ListedNeighborhood<'a, T, R> {
        ListedNeighborhood {
            grid: self.neighborhood(position, topology),
            list: View::new(&self.neighbor_list),
            kernels,
            spiky_gradient: View::new(spiky_gradient),
        }
    }

    /// Bytes of the grid's own arrays.
    pub fn bytes(&self) -> usize {
        4 * (self.cell_key.len() + self.counters.len() + self.cell_start.len() + self.order.len() + self.neighbor_list.len())
            + self.holds_fluid.len()
            + self.near_fluid.len()
    }

    /// Sorts the particles by cell, dropping those outside the domain; returns how many left.
    pub fn sort<R: Real>(&mut self, p: &mut Particles<R>) -> usize {
        let n = p.len();
        let grid = self.grid;
        let args = HashArgs { grid, position: p.position_view(), cell_key: view_mut(&mut self.cell_key, n) };
        launch(n, |i| hash_pass(i, &args));

        let counters = Counters::new(&self.counters);
        let buckets = self.counters.len();
        launch(buckets, |k| self.counters[k].store(0, Ordering::Relaxed));
        let keys = View::new(&self.cell_key[..n]);
        launch(n, |i| count_particle(i, keys, counters));

        // Exclusive scan: chunk totals in parallel, their offsets by levels, then each chunk.
        let chunks = buckets.div_ceil(SCAN_CHUNK);
        let levels = ViewMut::new(&mut self.chunk_offsets);
        let totals = levels.range(0, chunks);
        // SAFETY: invocation c writes only entry c.
        launch(chunks, |c| unsafe { totals.write(c, chunk_total(c, SCAN_CHUNK, counters)) });
        let level = |(start, len): (usize, usize)| levels.range(start, len);
        let scanned = scan_by_levels::<std::convert::Infallible>(chunks, |step| {
            match step {
                ScanStep::Up { values, sums } => {
                    let (values, sums) = (level(values).read(), level(sums));
                    // SAFETY: as above.
                    launch(sums.len(), |c| unsafe { sums.write(c, sum_chunk(c, values)) });
                }
                ScanStep::Top(top) => scan_chunk_offsets(level(top)),
                ScanStep::Down { values, offsets } => {
                    let (values, offsets) = (level(values), level(offsets).read());
                    launch(offsets.len(), |c| scan_chunk_in_place(c, offsets.at(c), values));
                }
            }
            Ok(())
        });
        let Ok(()) = scanned;
        let offsets = totals.read();
        let starts = ViewMut::new(&mut self.cell_start);
        launch(chunks, |c| scan_chunk(c, SCAN_CHUNK, offsets.at(c), counters, starts));

        let order = view_mut(&mut self.order, n);
        launch(n, |i| scatter(i, keys, counters, order));
        let starts = View::new(&self.cell_start);
        launch(grid.cell_count() as usize, |c| sort_bucket(c, starts, order));

        let live = self.cell_start[grid.cell_count() as usize] as usize;
        reorder(p, View::new(&self.order[..live]), live);
        self.mark_cells_near_fluid(View::new(&p.id[..live]));
        n - live
    }

    /// The `fluid_cells` passes over the sorted particles' ids, when the grid tracks fluid.
    fn mark_cells_near_fluid(&mut self, id: View<u32>) {
        let Some(boundary_count) = self.resting_boundary else {
            return;
        };
        let cells = self.holds_fluid.len();
        let args = HoldsFluidArgs {
            cell_start: View::new(&self.cell_start),
            id,
            boundary_count,
            holds_fluid: ViewMut::new(&mut self.holds_fluid),
        };
        launch(cells, |c| holds_fluid_pass(c, &args));
        let periodic = self.is_periodic();
        let (grid, cell_start) = (self.grid, View::new(&self.cell_start));
        let (holds_fluid, near_fluid) = (View::new(&self.holds_fluid), ViewMut::new(&mut self.near_fluid));
        if periodic {
            let args = NearFluidArgs { grid, topology: self.periodic, cell_start, holds_fluid, near_fluid };
            launch(cells, |c| near_fluid_pass(c, &args));
        } else {
            let args = NearFluidArgs { grid, topology: Open, cell_start, holds_fluid, near_fluid };
            launch(cells, |c| near_fluid_pass(c, &args));
        }
    }

    /// The start of each cell's run, for a backend that sorted elsewhere to fill in.
    #[cfg(feature = "cuda")]
    pub(crate) fn cell_start_mut(&mut self) -> &mut [u32] {
        &mut self.cell_start
    }

    /// The near-fluid marks, for a backend that sorted elsewhere to fill in.
    #[cfg(feature = "cuda")]
    pub(crate) fn near_fluid_mut(&mut self) -> &mut [u8] {
        &mut self.near_fluid
    }

    /// Whether any axis wraps.
    pub fn is_periodic(&self) -> bool {
        self.periodic.period.iter().any(|&l| l > 0.0)
    }

    /// The sorted grid for the particles' current order, in topology `topology`.
    pub fn neighborhood<'a, T: Topology>(&'a self, position: Vec3View<'a, f64>, topology: T) -> Neighborhood<'a, T> {
        Neighborhood {
            grid: self.grid,
            cell_start: View::new(&self.cell_start),
            position,
            topology,
            near_fluid: View::new(&self.near_fluid),
        }
    }
}

/// Permutes every field that carries state from step to step (positions, both velocities,
/// ids, and density where the continuity equation integrates it) into sorted order; fields
/// recomputed each step are left alone.
fn reorder<R: Real>(p: &mut Particles<R>, order: View<u32>, live: usize) {
    fn permute<T: Copy + Send + Sync>(
        field: &mut ParticleArray<T>,
        scratch: &mut ParticleArray<T>,
        order: View<u32>,
        live: usize,
    ) {
        let unsorted = View::new(&field[..]);
        let sorted = view_mut(scratch, live);
        launch(live, |k| gather(k, order, unsorted, sorted));
        std::mem::swap(field, scratch);
    }
    for a in 0..3 {
        permute(&mut p.position[a], &mut p.scratch_f64, order, live);
        permute(&mut p.velocity[a], &mut p.scratch_real, order, live);
        permute(&mut p.velocity_half[a], &mut p.scratch_real, order, live);
    }
    permute(&mut p.id, &mut p.scratch_u32, order, live);
    if p.density_is_state() {
        permute(&mut p.density, &mut p.scratch_real, order, live);
    }
    if let Some(implicit) = &mut p.implicit {
        for a in 0..3 {
            permute(&mut implicit.viscous_change[a], &mut p.scratch_real, order, live);
        }
    }
    if let Some(pressure) = &mut p.pressure_solve {
        for sum in &mut pressure.stiffness_sums {
            permute(sum, &mut p.scratch_real, order, live);
        }
    }
    p.set_len(live);
}
