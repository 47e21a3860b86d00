//! Per-run constants of the fluid and its particles, shared by every kernel.

use crate::real::Real;
use crate::smoothing::SmoothingKernels;
use crate::vec3::Vec3;

/// Constants of one run, in SI units.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct Fluid<R> {
    /// Mass of every particle m (kg).
    pub mass: R,
    /// Reference density rho0 (kg/m^3).
    pub rest_density: R,
    /// Squared speed of sound c^2 (m^2/s^2), Eq. (6).
    pub sound_speed2: R,
    /// Lowest pressure the equation of state returns (Pa): minus infinity keeps Eq. (6) as
    /// printed; 0 removes the tension that the density deficit of free-surface particles
    /// otherwise creates (c^2 times about 20 % of rho0), which grows with c^2.
    pub pressure_floor: R,
    /// Lowest density of a fixed boundary particle (kg/m^3), whose density is Eq. (5)'s sum:
    /// rho0 where the pressure is not clamped, 0 (no floor, the paper's walls) where it is. A
    /// wall's own surface particles lose part of their support to the empty side of the wall,
    /// not to tension in the liquid; with Eq. (6) as printed that deficit pulled the liquid
    /// into the wall (a shear-thinning jet's foot went through its plate). Floored, a wall
    /// pushes and never pulls.
    pub wall_density_floor: R,
    /// Weight of the pair pressure (p_i + p_j) in the pressure force: 1/2 is Eq. (7) as printed
    /// (Müller 2003's mean), which is half the gradient of a linear pressure field, so that the
    /// fluid compresses as if c were c / sqrt(2); 1 gives the full gradient.
    pub pressure_pair_weight: R,
    /// Where pressure is solved, the share of a fluid particle's stiffness that a wall
    /// particle beside it pushes back with on top of the particle's own: 0 (once) or 1
    /// (mirrored; `dfsph_bender2017`).
    pub wall_stiffness_share: R,
    /// Gravity g (m/s^2).
    pub gravity: Vec3<R>,
    pub kernels: SmoothingKernels<R>,
    /// Particles with an id below this are fixed boundary particles (paper Sec. III-B).
    pub boundary_count: u32,
}

impl<R: Real> Fluid<R> {
    #[inline(always)]
    pub fn is_boundary(&self, id: u32) -> bool {
        id < self.boundary_count
    }

    /// The density of a fixed boundary particle whose Eq. (5) sum is `summed` (kg/m^3).
    #[inline(always)]
    pub fn wall_density(&self, summed: R) -> R {
        summed.max(self.wall_density_floor)
    }
}
