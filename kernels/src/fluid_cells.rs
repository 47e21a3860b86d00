//! Cells near fluid (after the sort of Algorithm 1, line 3).
//!
//! Where no fluid lies in a particle's cell or the cells around it, every particle within h is a
//! fixed boundary particle, at rest unless mirrored walls move them. There the velocity
//! gradient of Eq. (8) is exactly zero, and [`crate::cell_grid::Neighborhood::near_fluid`] lets
//! it skip its neighbor loop: most of a plate or a tank's walls lies there. The two per-cell
//! passes below mark those cells; a run with mirrored walls marks every cell near fluid.

use crate::cell_grid::CellGrid;
use crate::topology::{Periodic, Topology};
use crate::view::{View, ViewMut};

/// Arguments of the pass that marks the cells holding fluid.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct HoldsFluidArgs<'a> {
    /// The start of each cell's run of sorted particles, as in `Neighborhood::cell_start`.
    pub cell_start: View<'a, u32>,
    /// Particle ids in sorted order.
    pub id: View<'a, u32>,
    /// Ids below this are fixed boundary particles (`Fluid::boundary_count`).
    pub boundary_count: u32,
    /// Per cell: 1 where it holds a fluid particle, else 0.
    pub holds_fluid: ViewMut<'a, u8>,
}

/// The holds-fluid pass for cell `c`.
#[inline(always)]
pub fn holds_fluid_pass(c: usize, a: &HoldsFluidArgs) {
    let (start, end) = (a.cell_start.at(c) as usize, a.cell_start.at(c + 1) as usize);
    let mut holds = 0;
    for j in start..end {
        if a.id.at(j) >= a.boundary_count {
            holds = 1;
            break;
        }
    }
    // SAFETY: invocation c owns entry c.
    unsafe { a.holds_fluid.write(c, holds) };
}

/// Arguments of the pass that marks the cells near fluid.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NearFluidArgs<'a, T> {
    pub grid: CellGrid,
    pub topology: T,
    pub cell_start: View<'a, u32>,
    /// The holds-fluid pass's marks.
    pub holds_fluid: View<'a, u8>,
    /// Per cell: 0 where it holds only fixed boundary particles and none of the (up to 26)
    /// cells around it holds fluid, else 1. An empty cell is marked 1: no boundary particle is
    /// in it, and a fluid particle may enter it before the next sort (frames read the grid
    /// after the step's move).
    pub near_fluid: ViewMut<'a, u8>,
}

/// The near-fluid pass for cell `c`: the cells around it are those the neighbor loop visits,
/// wrapped across periodic faces. Only cells of boundary particles look around them.
#[inline(always)]
pub fn near_fluid_pass<T: Topology>(c: usize, a: &NearFluidArgs<T>) {
    let near = a.holds_fluid.at(c) != 0 || a.cell_start.at(c) == a.cell_start.at(c + 1) || holds_fluid_around(c, a);
    // SAFETY: invocation c owns entry c.
    unsafe { a.near_fluid.write(c, near as u8) };
}

/// Whether a cell around cell `c` holds fluid.
#[inline(always)]
fn holds_fluid_around<T: Topology>(c: usize, a: &NearFluidArgs<T>) -> bool {
    let cell = a.grid.cell_of_index(c as u32);
    let wrap = Periodic { origin: a.grid.origin, period: a.topology.periods() };
    for dz in -1..=1 {
        let Some(z) = wrap.neighbor_cell(2, a.grid.dims[2], cell[2], dz) else { continue };
        for dy in -1..=1 {
            let Some(y) = wrap.neighbor_cell(1, a.grid.dims[1], cell[1], dy) else { continue };
            for dx in -1..=1 {
                let Some(x) = wrap.neighbor_cell(0, a.grid.dims[0], cell[0], dx) else { continue };
                if a.holds_fluid.at(a.grid.linear_index([x, y, z]) as usize) != 0 {
                    return true;
                }
            }
        }
    }
    false
}
