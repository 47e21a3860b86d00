//! The uniform neighbor grid: cell hashing (Algorithm 1, line 3) and the 27-cell neighbor loop.
//!
//! Cells are boxes of edge at least h covering the domain box (h along open axes; along a
//! periodic axis the period split into whole cells), linearly indexed with x fastest. Particles
//! are kept sorted by cell, so a cell's particles are the contiguous run
//! `cell_start[c] .. cell_start[c + 1]` and x-adjacent cells form one run.

use crate::real::Real;
use crate::smoothing::SmoothingKernels;
use crate::topology::{minimum_image, Open, Periodic, Topology};
use crate::vec3::Vec3;
use crate::view::{Vec3View, View, ViewMut};

/// Geometry of the cell grid (positions in m).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellGrid {
    /// Lower corner of the domain box (m).
    pub origin: [f64; 3],
    /// 1 / cell edge along each axis (1/m); every edge is at least the support radius h.
    pub inverse_cell_size: [f64; 3],
    /// Cells along x, y, z.
    pub dims: [u32; 3],
}

impl CellGrid {
    /// Number of cells; also the key of the bucket that collects particles outside the domain.
    #[inline(always)]
    pub fn cell_count(&self) -> u32 {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Integer cell coordinates of a position, or `None` outside the domain box.
    #[inline(always)]
    pub fn cell_coords(&self, p: [f64; 3]) -> Option<[u32; 3]> {
        let mut c = [0u32; 3];
        for a in 0..3 {
            let f = (p[a] - self.origin[a]) * self.inverse_cell_size[a];
            // `!(f >= 0)` also rejects NaN.
            if !(f >= 0.0) || f >= self.dims[a] as f64 {
                return None;
            }
            c[a] = f as u32;
        }
        Some(c)
    }

    #[inline(always)]
    pub fn linear_index(&self, c: [u32; 3]) -> u32 {
        c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])
    }

    /// Integer cell coordinates of linear index `c`: the inverse of [`Self::linear_index`].
    #[inline(always)]
    pub fn cell_of_index(&self, c: u32) -> [u32; 3] {
        // Every dimension is at least 1; checked division keeps the divide-by-zero trap out of
        // the device code.
        let row = c.checked_div(self.dims[0]).unwrap_or(0);
        let layer = row.checked_div(self.dims[1]).unwrap_or(0);
        [c - row * self.dims[0], row - layer * self.dims[1], layer]
    }
}

/// Cell key of particle `i`: its linear cell index, or `cell_count()` when it has left the
/// domain box (it is then sorted past every live particle and dropped).
#[inline(always)]
pub fn hash(i: usize, grid: &CellGrid, position: &Vec3View<f64>) -> u32 {
    match grid.cell_coords(position.at(i)) {
        Some(c) => grid.linear_index(c),
        None => grid.cell_count(),
    }
}

/// Arguments of the hashing pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct HashArgs<'a> {
    pub grid: CellGrid,
    pub position: Vec3View<'a, f64>,
    pub cell_key: ViewMut<'a, u32>,
}

/// The hashing pass for particle `i`.
#[inline(always)]
pub fn hash_pass(i: usize, a: &HashArgs) {
    // SAFETY: invocation i owns entry i.
    unsafe { a.cell_key.write(i, hash(i, &a.grid, &a.position)) };
}

/// The sorted grid that neighbor loops read, in a domain of topology `T`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct Neighborhood<'a, T = Open> {
    pub grid: CellGrid,
    /// `cell_count() + 2` entries: the start of each cell's run, then the live-particle count,
    /// then the total including particles that left the domain.
    pub cell_start: View<'a, u32>,
    /// Particle positions (m), sorted by cell. Kept in f64 so that slow particles never lose
    /// motion far from the origin; differences are taken in f64 and then rounded to `R`.
    pub position: Vec3View<'a, f64>,
    pub topology: T,
    /// `cell_count()` entries: non-zero where fluid may lie within h of the cell's particles
    /// (`fluid_cells`).
    pub near_fluid: View<'a, u8>,
}

/// The body of a sum over a particle's neighbors with the kernel gradient
/// ([`Neighbors::sum_spiky_gradients`]). A type with an always-inlined method, not a closure: the
/// solvers' loops run 20 to 40 times a step, and a closure's body beyond the compiler's inlining
/// threshold became a call per pair, with its sums kept in memory, which took half their time.
pub trait GradientSum<R> {
    /// Adds neighbor `j`, with grad_i W(x_ij) (1/m^4).
    fn add(&mut self, j: usize, grad_w: Vec3<R>);
}

/// The particles within h of a particle, as the neighbor passes (density, velocity gradient,
/// accelerations) visit them: through the cells of the grid ([`Neighborhood`]), or through the
/// list the CPU backend records once a step ([`crate::neighbor_list::ListedNeighborhood`]).
/// Both visit the same particles in the same order with the same offsets, so a pass's sums,
/// and so a run, are the same to the bit either way.
pub trait Neighbors: Copy {
    /// Calls `f(j, x_i - x_j, |x_i - x_j|^2)` for every particle j with |x_i - x_j| < h,
    /// including i itself, in a fixed order (cells in index order, then sorted order). Across a
    /// periodic face x_i - x_j is the nearest image's.
    fn for_each_neighbor<R: Real, F: FnMut(usize, Vec3<R>, R)>(&self, i: usize, h2: R, f: F);

    /// Adds to `sum` each particle j of [`Self::for_each_neighbor`] with `kernels`' spiky
    /// gradient grad_i W(x_ij) (1/m^4), in its order and to the same bits as
    /// `kernels.spiky_gradient(x_i - x_j, |x_i - x_j|^2)`.
    #[inline(always)]
    fn sum_spiky_gradients<R: Real, S: GradientSum<R>>(&self, i: usize, kernels: &SmoothingKernels<R>, sum: &mut S) {
        self.for_each_neighbor(i, kernels.h2, |j, r_ij, r2| sum.add(j, kernels.spiky_gradient(r_ij, r2)));
    }

    /// Whether fluid may lie within h of particle `i`; false where every particle within h is a
    /// fixed boundary particle (`fluid_cells`), or where `i` has left the domain box and the
    /// neighbor loop finds nothing.
    fn near_fluid(&self, i: usize) -> bool;
}

impl<T: Topology> Neighbors for Neighborhood<'_, T> {
    #[inline(always)]
    fn for_each_neighbor<R: Real, F: FnMut(usize, Vec3<R>, R)>(&self, i: usize, h2: R, f: F) {
        self.for_each_particle_near(self.position.at(i), h2, f);
    }

    #[inline(always)]
    fn near_fluid(&self, i: usize) -> bool {
        match self.grid.cell_coords(self.position.at(i)) {
            Some(c) => self.near_fluid.at(self.grid.linear_index(c) as usize) != 0,
            None => false,
        }
    }
}

impl<T: Topology> Neighborhood<'_, T> {
    /// x - x_j (m) and |x - x_j|^2 (m^2) for a point `x` and particle `j`, in f64: across a
    /// periodic face the nearest image's. Every neighbor loop takes them from here, so the grid's
    /// loops and the lists give the same bits.
    #[inline(always)]
    pub fn separation(&self, x: [f64; 3], j: usize) -> ([f64; 3], f64) {
        let d = [x[0] - self.position.x.at(j), x[1] - self.position.y.at(j), x[2] - self.position.z.at(j)];
        let d = if T::PERIODIC {
            let period = self.topology.periods();
            [minimum_image(d[0], period[0]), minimum_image(d[1], period[1]), minimum_image(d[2], period[2])]
        } else {
            d
        };
        (d, d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    }

    /// Calls `f(j, x - x_j, |x - x_j|^2)` for every particle j with |x - x_j| < h around a point
    /// `x` of the domain (m), in the order of [`Neighbors::for_each_neighbor`]; none when `x` lies
    /// outside the domain box.
    #[inline(always)]
    pub fn for_each_particle_near<R: Real, F: FnMut(usize, Vec3<R>, R)>(&self, x: [f64; 3], h2: R, f: F) {
        if T::PERIODIC {
            self.for_each_particle_near_periodic(x, h2, f);
        } else {
            self.for_each_particle_near_open(x, h2, f);
        }
    }

    /// The open domain's loop: three x-adjacent cells are one contiguous run.
    #[inline(always)]
    fn for_each_particle_near_open<R: Real, F: FnMut(usize, Vec3<R>, R)>(&self, xi: [f64; 3], h2: R, mut f: F) {
        let Some(c) = self.grid.cell_coords(xi) else {
            return;
        };
        // Candidates are filtered in f64 and only neighbors are rounded to `R`: about 6 of 7
        // candidates in the 27 cells lie outside the support.
        let h2_f64 = h2.to_f64();
        let dims = self.grid.dims;
        let x_lo = c[0].saturating_sub(1);
        let x_hi = if c[0] + 1 < dims[0] { c[0] + 1 } else { c[0] };
        for z in c[2].saturating_sub(1)..=(c[2] + 1).min(dims[2] - 1) {
            for y in c[1].saturating_sub(1)..=(c[1] + 1).min(dims[1] - 1) {
                let first = self.grid.linear_index([x_lo, y, z]) as usize;
                let last = self.grid.linear_index([x_hi, y, z]) as usize;
                let start = self.cell_start.at(first) as usize;
                let end = self.cell_start.at(last + 1) as usize;
                R::tally_candidates(end - start);
                for j in start..end {
                    let (r_ij, r2) = self.separation(xi, j);
                    if r2 < h2_f64 {
                        f(j, Vec3::from_f64(r_ij), R::from_f64(r2));
                    }
                }
            }
        }
    }

    /// The periodic domain's loop: cells wrap along periodic axes (which hold at least 3 cells,
    /// so no cell is visited twice), and x-runs split where they cross the seam.
    #[inline(always)]
    fn for_each_particle_near_periodic<R: Real, F: FnMut(usize, Vec3<R>, R)>(&self, xi: [f64; 3], h2: R, mut f: F) {
        let Some(c) = self.grid.cell_coords(xi) else {
            return;
        };
        let period = self.topology.periods();
        let wrap = Periodic { origin: self.grid.origin, period };
        let h2_f64 = h2.to_f64();
        let dx_cells = self.grid.dims[0];
        // The x cells c-1..=c+1 as at most two contiguous runs, held in scalars: an array
        // indexed in the loop would live in the device's local memory.
        let (first, second) = if period[0] > 0.0 && c[0] == 0 {
            ((0, 1), Some((dx_cells - 1, dx_cells - 1)))
        } else if period[0] > 0.0 && c[0] == dx_cells - 1 {
            ((0, 0), Some((dx_cells - 2, dx_cells - 1)))
        } else {
            ((c[0].saturating_sub(1), if c[0] + 1 < dx_cells { c[0] + 1 } else { c[0] }), None)
        };
        let mut run = |(x_lo, x_hi): (u32, u32), y: u32, z: u32| {
            let start = self.cell_start.at(self.grid.linear_index([x_lo, y, z]) as usize) as usize;
            let end = self.cell_start.at(self.grid.linear_index([x_hi, y, z]) as usize + 1) as usize;
            R::tally_candidates(end - start);
            for j in start..end {
                let (r_ij, r2) = self.separation(xi, j);
                if r2 < h2_f64 {
                    f(j, Vec3::from_f64(r_ij), R::from_f64(r2));
                }
            }
        };
        for dz in -1..=1 {
            let Some(z) = wrap.neighbor_cell(2, self.grid.dims[2], c[2], dz) else { continue };
            for dy in -1..=1 {
                let Some(y) = wrap.neighbor_cell(1, self.grid.dims[1], c[1], dy) else { continue };
                run(first, y, z);
                if let Some(second) = second {
                    run(second, y, z);
                }
            }
        }
    }
}
