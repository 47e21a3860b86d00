//! Neighbor lists: each particle's neighbors within h, recorded once a step, after the sort,
//! by the CPU backend.
//!
//! Three passes a step loop over a particle's neighbors (density, velocity gradient and
//! stress, accelerations), and through the grid each filters about 180 candidates in the 27
//! cells for about 33 neighbors; on a CPU the filter and its mispredicted branches took most
//! of a step. Recording the neighbors once lets the later passes visit them directly. The
//! device does not record them: at `NEIGHBOR_SLOTS` u32 a particle the list alone would
//! take 192 bytes a particle, against the 200 its whole state may take.

use crate::cell_grid::{Neighborhood, Neighbors};
use crate::real::Real;
use crate::topology::Topology;
use crate::vec3::Vec3;
use crate::view::{View, ViewMut};

/// Slots per particle: its neighbor count, then up to `NEIGHBOR_SLOTS - 1` neighbor indices.
/// A particle has about 33 neighbors at rest (h = 2 spacings) and up to 45 were seen in a
/// jet's impact; one with more is visited through the grid.
pub const NEIGHBOR_SLOTS: usize = 48;

/// Arguments of the pass that records the neighbor lists.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NeighborListArgs<'a, R, T> {
    pub neighborhood: Neighborhood<'a, T>,
    /// The squared support radius (m^2) of the passes that read the list.
    pub h2: R,
    /// `NEIGHBOR_SLOTS` entries per particle.
    pub list: ViewMut<'a, u32>,
}

/// Records particle `i`'s neighbors, in the grid's order.
#[inline(always)]
pub fn neighbor_list_pass<R: Real, T: Topology>(i: usize, a: &NeighborListArgs<R, T>) {
    let base = i * NEIGHBOR_SLOTS;
    let mut count = 0;
    a.neighborhood.for_each_neighbor(i, a.h2, |j, _, _: R| {
        count += 1;
        if count < NEIGHBOR_SLOTS {
            // SAFETY: invocation i owns slots base .. base + NEIGHBOR_SLOTS.
            unsafe { a.list.write(base + count, j as u32) };
        }
    });
    // SAFETY: as above.
    unsafe { a.list.write(base, count as u32) };
}

/// The grid's neighbors of each particle as recorded by [`neighbor_list_pass`] over the same
/// positions, for the passes of the same step; particles with more neighbors than the slots
/// hold are visited through the grid.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ListedNeighborhood<'a, T> {
    pub grid: Neighborhood<'a, T>,
    pub list: View<'a, u32>,
}

impl<T: Topology> Neighbors for ListedNeighborhood<'_, T> {
    /// The recorded neighbors, with offsets computed as the grid's loop computes them; `h2`
    /// must be the radius the list was recorded for.
    #[inline(always)]
    fn for_each_neighbor<R: Real, F: FnMut(usize, Vec3<R>, R)>(&self, i: usize, h2: R, mut f: F) {
        let base = i * NEIGHBOR_SLOTS;
        let count = self.list.at(base) as usize;
        if count >= NEIGHBOR_SLOTS {
            return self.grid.for_each_neighbor(i, h2, f);
        }
        let xi = self.grid.position.at(i);
        for k in base + 1..=base + count {
            let j = self.list.at(k) as usize;
            let (r_ij, r2) = self.grid.separation(xi, j);
            f(j, Vec3::from_f64(r_ij), R::from_f64(r2));
        }
    }

    #[inline(always)]
    fn near_fluid(&self, i: usize) -> bool {
        self.grid.near_fluid(i)
    }
}
