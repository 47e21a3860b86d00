//! Density and pressure (Algorithm 1, lines 6-7).

use crate::cell_grid::Neighborhood;
use crate::fluid::Fluid;
use crate::real::Real;
use crate::topology::{Open, Topology};
use crate::view::ViewMut;

/// Density by direct summation with poly6, Eq. (5): rho_i = sum_j m_j W(x_ij) (kg/m^3).
/// Boundary particles get theirs the same way (paper Sec. III-B).
#[inline(always)]
pub fn density<R: Real, T: Topology>(i: usize, neighborhood: &Neighborhood<T>, fluid: &Fluid<R>) -> R {
    let mut sum = R::ZERO;
    neighborhood.for_each_neighbor(i, fluid.kernels.h2, |_, _, r2: R| sum += fluid.kernels.poly6(r2));
    sum * fluid.mass
}

/// Equation of state, Eq. (6): p = c^2 (rho - rho0) (Pa), floored at `fluid.pressure_floor`.
#[inline(always)]
pub fn pressure<R: Real>(density: R, fluid: &Fluid<R>) -> R {
    (fluid.sound_speed2 * (density - fluid.rest_density)).max(fluid.pressure_floor)
}

/// Arguments of the density pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct DensityArgs<'a, R, T = Open> {
    pub neighborhood: Neighborhood<'a, T>,
    pub fluid: Fluid<R>,
    pub density: ViewMut<'a, R>,
}

/// The density pass for particle `i`. Pressure is not stored: Eq. (6) is cheaper to evaluate
/// where it is read than to load.
#[inline(always)]
pub fn density_pass<R: Real, T: Topology>(i: usize, a: &DensityArgs<R, T>) {
    // SAFETY: invocation i owns entry i.
    unsafe { a.density.write(i, density(i, &a.neighborhood, &a.fluid)) };
}
