//! The cell grid over the domain and, for the particles in their sorted order, where each
//! cell's run starts and which cells lie near fluid: what every neighbor visit reads, on
//! either backend. How a backend sorts into it is its own (`cpu::neighbor_grid`, the CUDA
//! backend's device arrays).

use coil_kernels::cell_grid::{CellGrid, Neighborhood};
use coil_kernels::topology::{Periodic, Topology, PERIODIC_ROUNDING};
use coil_kernels::view::{Vec3View, View};

pub struct SortedGrid {
    pub grid: CellGrid,
    /// The domain's periods (0 along open axes; all 0 for an open domain).
    pub periodic: Periodic,
    /// Per bucket (the cells, then the one for particles outside the domain), where its run of
    /// sorted particles starts; one entry more for the end.
    cell_start: Vec<u32>,
    /// Per cell: whether it lies near fluid (`coil_kernels::fluid_cells`).
    near_fluid: Vec<u8>,
    /// Ids below this are fixed boundary particles at rest, whose cells each sort marks; `None`
    /// marks every cell near fluid.
    resting_boundary: Option<u32>,
}

impl SortedGrid {
    /// A grid of cells of edge `cell_size` (m, the support radius) over the domain box; along
    /// the axes marked `periodic` the box length is split into whole cells of at least that edge,
    /// less `PERIODIC_ROUNDING` of it.
    pub fn new(min: [f64; 3], max: [f64; 3], cell_size: f64, periodic: [bool; 3]) -> Self {
        let length = [0, 1, 2].map(|a| max[a] - min[a]);
        let dims = [0, 1, 2].map(|a| {
            let cells = length[a] / cell_size;
            (if periodic[a] { (cells * (1.0 + PERIODIC_ROUNDING)).floor() } else { cells.ceil() } as u32).max(1)
        });
        let inverse_cell_size = [0, 1, 2].map(|a| if periodic[a] { dims[a] as f64 / length[a] } else { 1.0 / cell_size });
        let grid = CellGrid { origin: min, inverse_cell_size, dims };
        let periodic = Periodic { origin: min, period: [0, 1, 2].map(|a| if periodic[a] { length[a] } else { 0.0 }) };
        let cells = grid.cell_count() as usize;
        Self { grid, periodic, cell_start: vec![0; cells + 2], near_fluid: vec![1; cells], resting_boundary: None }
    }

    /// Cells and the bucket of particles outside the domain.
    pub fn buckets(&self) -> usize {
        self.grid.cell_count() as usize + 1
    }

    /// From the next sort on, marks the cells near fluid, for particles whose ids below
    /// `boundary_count` are fixed boundary particles that stay at rest (not mirrored walls).
    pub fn track_fluid(&mut self, boundary_count: u32) {
        self.resting_boundary = Some(boundary_count);
    }

    /// The boundary count the sorts mark the cells near fluid by; `None` where every cell
    /// counts as near fluid.
    pub fn tracks_fluid(&self) -> Option<u32> {
        self.resting_boundary
    }

    /// Whether any axis wraps.
    pub fn is_periodic(&self) -> bool {
        self.periodic.period.iter().any(|&l| l > 0.0)
    }

    /// The start of each bucket's run, as the last sort left it.
    pub fn cell_start(&self) -> &[u32] {
        &self.cell_start
    }

    /// The near-fluid marks, as the last sort left them.
    pub fn near_fluid(&self) -> &[u8] {
        &self.near_fluid
    }

    /// The start of each bucket's run, for a sort to fill in.
    pub fn cell_start_mut(&mut self) -> &mut [u32] {
        &mut self.cell_start
    }

    /// The near-fluid marks, for a sort to fill in.
    pub fn near_fluid_mut(&mut self) -> &mut [u8] {
        &mut self.near_fluid
    }

    /// The start of each bucket's run, and the near-fluid marks to fill in.
    pub fn starts_and_marks(&mut self) -> (View<'_, u32>, &mut [u8]) {
        (View::new(&self.cell_start), &mut self.near_fluid)
    }

    /// Live particles after the last sort: those in the domain's cells.
    pub fn live(&self) -> usize {
        self.cell_start[self.grid.cell_count() as usize] as usize
    }

    /// Bytes of the grid's arrays.
    pub fn bytes(&self) -> usize {
        4 * self.cell_start.len() + self.near_fluid.len()
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
