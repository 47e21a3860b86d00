//! Neighbor lists: each particle's neighbors within h, recorded once a step, after the sort,
//! by the CPU backend, and, for the solvers that loop over them many times a step, each pair's
//! spiky kernel gradient.
//!
//! Three passes a step loop over a particle's neighbors (density, velocity gradient and
//! stress, accelerations), and through the grid each filters about 180 candidates in the 27
//! cells for about 33 neighbors; on a CPU the filter and its mispredicted branches took most
//! of a step. Recording the neighbors once lets the later passes visit them directly. An
//! implicit viscosity solve and a pressure solve visit them 20 to 40 times a step, each time
//! taking the offset in f64, a square root and a division for the same gradient: recorded
//! once, the gradient is a read. The device does not record them: at `NEIGHBOR_SLOTS` u32 a
//! particle the list alone would take 192 bytes a particle, against the 200 its whole state
//! may take.

use crate::cell_grid::{GradientSum, Neighborhood, Neighbors};
use crate::real::Real;
use crate::smoothing::SmoothingKernels;
use crate::topology::Topology;
use crate::vec3::Vec3;
use crate::view::{View, ViewMut};
use core::any::TypeId;

/// Slots per particle: its neighbor count, then up to `NEIGHBOR_SLOTS - 1` neighbor indices.
/// A particle has about 33 neighbors at rest (h = 2 spacings) and up to 45 were seen in a
/// jet's impact; one with more is visited through the grid.
pub const NEIGHBOR_SLOTS: usize = 48;

/// Arguments of the pass that records the neighbor lists.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NeighborListArgs<'a, R, T> {
    pub neighborhood: Neighborhood<'a, T>,
    /// The kernels of the passes that read the list: its radius is theirs.
    pub kernels: SmoothingKernels<R>,
    /// `NEIGHBOR_SLOTS` entries per particle.
    pub list: ViewMut<'a, u32>,
    /// `NEIGHBOR_SLOTS` entries per particle, each listed neighbor's spiky gradient (1/m^4) in
    /// its slot; empty where the gradients are not kept.
    pub spiky_gradient: ViewMut<'a, [R; 3]>,
}

/// Records particle `i`'s neighbors, in the grid's order, and their gradients where kept. A
/// boundary particle away from fluid gets an empty list: no pass reads its neighbors (on a
/// jet's plate most of the wall particles, a third of a small scene's particles).
#[inline(always)]
pub fn neighbor_list_pass<R: Real, T: Topology>(i: usize, a: &NeighborListArgs<R, T>) {
    let base = i * NEIGHBOR_SLOTS;
    if !a.neighborhood.near_fluid(i) {
        // SAFETY: as below.
        unsafe { a.list.write(base, 0) };
        return;
    }
    let gradients = !a.spiky_gradient.is_empty();
    let mut count = 0;
    a.neighborhood.for_each_neighbor(i, a.kernels.h2, |j, r_ij, r2: R| {
        count += 1;
        if count < NEIGHBOR_SLOTS {
            // SAFETY: invocation i owns slots base .. base + NEIGHBOR_SLOTS.
            unsafe { a.list.write(base + count, j as u32) };
            if gradients {
                let g = a.kernels.spiky_gradient(r_ij, r2);
                // SAFETY: as above.
                unsafe { a.spiky_gradient.write(base + count, [g.x, g.y, g.z]) };
            }
        }
    });
    // SAFETY: as above.
    unsafe { a.list.write(base, count as u32) };
}

/// The grid's neighbors of each particle as recorded by [`neighbor_list_pass`] over the same
/// positions, for the passes of the same step; particles with more neighbors than the slots
/// hold are visited through the grid. `C` is the precision the gradients were recorded in.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ListedNeighborhood<'a, T, C = f32> {
    pub grid: Neighborhood<'a, T>,
    pub list: View<'a, u32>,
    /// The kernels the gradients were recorded with.
    pub kernels: SmoothingKernels<C>,
    /// The recorded gradients, empty where none were.
    pub spiky_gradient: View<'a, [C; 3]>,
}

impl<T: Topology, C: Real> ListedNeighborhood<'_, T, C> {
    /// Whether the recorded gradients are those `kernels` gives in precision `R`.
    #[inline(always)]
    fn recorded_for<R: Real>(&self, kernels: &SmoothingKernels<R>) -> bool {
        TypeId::of::<R>() == TypeId::of::<C>()
            && !self.spiky_gradient.is_empty()
            && kernels.h2.to_f64() == self.kernels.h2.to_f64()
            && kernels.spiky_gradient_coefficient().to_f64() == self.kernels.spiky_gradient_coefficient().to_f64()
    }
}

impl<T: Topology, C: Real> Neighbors for ListedNeighborhood<'_, T, C> {
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

    /// The recorded gradients where they were recorded with `kernels` in `R` (the conversion
    /// through f64 is then exact), computed otherwise.
    #[inline(always)]
    fn sum_spiky_gradients<R: Real, S: GradientSum<R>>(&self, i: usize, kernels: &SmoothingKernels<R>, sum: &mut S) {
        let base = i * NEIGHBOR_SLOTS;
        let count = self.list.at(base) as usize;
        if count >= NEIGHBOR_SLOTS || !self.recorded_for(kernels) {
            return self.for_each_neighbor(i, kernels.h2, |j, r_ij, r2| sum.add(j, kernels.spiky_gradient(r_ij, r2)));
        }
        for k in base + 1..=base + count {
            let [x, y, z] = self.spiky_gradient.at(k);
            let grad = Vec3::new(R::from_f64(x.to_f64()), R::from_f64(y.to_f64()), R::from_f64(z.to_f64()));
            sum.add(self.list.at(k) as usize, grad);
        }
    }

    #[inline(always)]
    fn near_fluid(&self, i: usize) -> bool {
        self.grid.near_fluid(i)
    }
}
