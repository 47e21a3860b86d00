//! Density and pressure (Algorithm 1, lines 6-7).

use crate::cell_grid::{Neighborhood, Neighbors};
use crate::fluid::Fluid;
use crate::real::Real;
use crate::smoothing::SmoothingKernels;
use crate::topology::Open;
use crate::view::{View, ViewMut};
use core::fmt::Debug;

/// The kernel W of the density sum, Eq. (5), fixed for a run.
pub trait DensityKernel: Copy + Debug + Default + Send + Sync + 'static {
    /// Variant of the PTX entries built for this kernel ("" for the paper's poly6).
    const NAME: &'static str;
    /// W(r) (1/m^3) at squared distance `r2` (m^2).
    fn weight<R: Real>(kernels: &SmoothingKernels<R>, r2: R) -> R;
}

/// The paper's (Müller 2003's) poly6. It is not the kernel whose gradient Eq. (7) takes (the
/// spiky one), so the pressure force does not follow the gradient of the density it comes
/// from, and a lattice stiffened by a high c flutters where viscosity no longer damps the
/// particle scale (`coil tradeoff`'s Mach 1e-4 channel).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Poly6;

impl DensityKernel for Poly6 {
    const NAME: &'static str = "";
    #[inline(always)]
    fn weight<R: Real>(kernels: &SmoothingKernels<R>, r2: R) -> R {
        kernels.poly6(r2)
    }
}

/// The spiky kernel, whose gradient Eq. (7), (8) and (9) already use.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spiky;

impl DensityKernel for Spiky {
    const NAME: &'static str = "spiky";
    #[inline(always)]
    fn weight<R: Real>(kernels: &SmoothingKernels<R>, r2: R) -> R {
        kernels.spiky(r2)
    }
}

/// Density by direct summation, Eq. (5): rho_i = sum_j m_j W(x_ij) (kg/m^3), W being `K`.
/// Boundary particles get theirs the same way (paper Sec. III-B).
#[inline(always)]
pub fn density<R: Real, K: DensityKernel, N: Neighbors>(i: usize, neighborhood: &N, fluid: &Fluid<R>) -> R {
    let mut sum = R::ZERO;
    neighborhood.for_each_neighbor(i, fluid.kernels.h2, |_, _, r2: R| sum += K::weight(&fluid.kernels, r2));
    sum * fluid.mass
}

/// Equation of state, Eq. (6): p = c^2 (rho - rho0) (Pa), floored at `fluid.pressure_floor`.
#[inline(always)]
pub fn pressure<R: Real>(density: R, fluid: &Fluid<R>) -> R {
    (fluid.sound_speed2 * (density - fluid.rest_density)).max(fluid.pressure_floor)
}

/// The density of fixed boundary particle `i` (kg/m^3): its Eq. (5) sum with kernel `K`,
/// floored by [`Fluid::wall_density`]. Away from fluid no fluid particle reads it, and it takes
/// rho0 without a neighbor loop: the wall particles beside the fluid divide by it in their
/// velocity gradient, Eq. (8), whose terms between walls at rest are zero, so any positive
/// density leaves them as they are.
#[inline(always)]
pub fn boundary_density<R: Real, K: DensityKernel, N: Neighbors>(i: usize, neighborhood: &N, fluid: &Fluid<R>) -> R {
    if neighborhood.near_fluid(i) {
        fluid.wall_density(density::<R, K, N>(i, neighborhood, fluid))
    } else {
        fluid.rest_density
    }
}

/// Arguments of the density pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct DensityArgs<'a, R, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    pub id: View<'a, u32>,
    pub density: ViewMut<'a, R>,
}

/// The density pass for particle `i` with the density kernel `K`, fixed boundary particles'
/// by [`boundary_density`]. Pressure is not stored: Eq. (6) is cheaper to evaluate where it is
/// read than to load.
#[inline(always)]
pub fn density_pass<R: Real, K: DensityKernel, N: Neighbors>(i: usize, a: &DensityArgs<R, N>) {
    let rho = if a.fluid.is_boundary(a.id.at(i)) {
        boundary_density::<R, K, N>(i, &a.neighborhood, &a.fluid)
    } else {
        density::<R, K, N>(i, &a.neighborhood, &a.fluid)
    };
    // SAFETY: invocation i owns entry i.
    unsafe { a.density.write(i, rho) };
}

/// The step's first density pass where pressure is solved on the continuity density: fixed
/// boundary particle `i`'s density by [`boundary_density`]; a fluid particle's integrated
/// density, raised to its Eq. (5) sum where the sum is higher.
///
/// The continuity equation integrates the density the solve predicted from each step's
/// positions, and the particles then move a little otherwise (the drift's curvature over a
/// CFL step, particle shifting), so in a pile, sheared for tenths of a second, the particles'
/// own packing creeps away from it: a 10-across jet's pile from H/D = 3 packed 1.3 to 1.7 times
/// closer than its density said by 0.6 s, which the solve could not see, and blew up. Where the
/// sum is higher the particles are packed closer than the density says, and the solve then
/// pushes them apart; where it is lower, at a free surface whose sum falls short, the
/// integrated density stays, and with it the solve's pull that thins a stretching thread.
#[inline(always)]
pub fn continuity_floor_pass<R: Real, K: DensityKernel, N: Neighbors>(i: usize, a: &DensityArgs<R, N>) {
    let rho = if a.fluid.is_boundary(a.id.at(i)) {
        boundary_density::<R, K, N>(i, &a.neighborhood, &a.fluid)
    } else {
        density::<R, K, N>(i, &a.neighborhood, &a.fluid).max(a.density.at(i))
    };
    // SAFETY: invocation i owns entry i.
    unsafe { a.density.write(i, rho) };
}
