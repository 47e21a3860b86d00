//! Per-particle viscosity for Morris's operator with a shear-thinning fluid: nu_i = nu(D_i),
//! Eq. (3), at the shear rate D_i of Eq. (2) from the velocity gradient of Eq. (8).
//!
//! The paper's operator differentiates twice with first-derivative sums (Eq. (8), then (9)),
//! whose product ignores a velocity that alternates from one particle layer to the next.
//! Morris's Laplacian sees that mode; this pass lets it carry a shear-thinning viscosity too.

use crate::cell_grid::{Neighborhood, Neighbors};
use crate::cross_viscosity::Rheology;
use crate::fluid::Fluid;
use crate::real::Real;
use crate::topology::Open;
use crate::velocity_gradient::{rate_of_deformation, shear_rate, velocity_gradient};
use crate::view::{Vec3View, View, ViewMut};

/// Arguments of the viscosity pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ShearViscosityArgs<'a, R, Rh, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    pub rheology: Rh,
    /// Velocity the viscous terms read (m/s): see `leapfrog`.
    pub velocity: Vec3View<'a, R>,
    pub density: View<'a, R>,
    /// Kinematic viscosity nu(D) (m^2/s).
    pub viscosity: ViewMut<'a, R>,
}

/// The viscosity pass for particle `i` (boundary particles included: the pair viscosity of
/// Morris's operator reads theirs).
#[inline(always)]
pub fn shear_viscosity_pass<R: Real, Rh: Rheology<R>, N: Neighbors>(i: usize, a: &ShearViscosityArgs<R, Rh, N>) {
    let grad = velocity_gradient(i, &a.neighborhood, &a.velocity, &a.density, &a.fluid);
    let nu = a.rheology.viscosity(shear_rate(rate_of_deformation(grad)));
    // SAFETY: invocation i owns entry i.
    unsafe { a.viscosity.write(i, nu) };
}
