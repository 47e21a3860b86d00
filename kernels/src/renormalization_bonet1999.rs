//! Eq. (8) renormalized to be exact for linear velocity fields: Bonet and Lok, "Variational and
//! momentum preservation aspects of Smooth Particle Hydrodynamic formulations" (CMAME 1999).
//! Where a free surface cuts a particle's support, Eq. (8) sees only part of the neighbors a
//! gradient needs (about half on a flat surface), so a stretching thread, which is mostly
//! surface, carries too little viscous stress; the correction restores most of it.

use crate::cell_grid::Neighbors;
use crate::fluid::Fluid;
use crate::real::Real;
use crate::vec3::Mat3;
use crate::velocity_gradient::{kernel_sums, GradientEstimate};
use crate::view::{Vec3View, View};

/// grad v_i = [sum_j V_j (v_j - v_i) ⊗ grad_i W_ij] · L_i^-1, with the moment matrix
/// L_i = sum_j V_j (x_j - x_i) ⊗ grad_i W_ij and V_j = m_j / rho_j (m^3): L_i is the identity
/// inside the fluid on a lattice, and L_i^-1 undoes the truncation of the support at a surface.
/// Where L_i is nearly singular (neighbors on one line or plane) it is Eq. (8) as printed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Renormalized;

impl GradientEstimate for Renormalized {
    const NAME: &'static str = "renormalized";
    #[inline(always)]
    fn velocity_gradient<R: Real, N: Neighbors>(
        i: usize,
        neighborhood: &N,
        velocity: &Vec3View<R>,
        density: &View<R>,
        fluid: &Fluid<R>,
    ) -> Mat3<R> {
        kernel_sums::<R, N, true, false>(i, neighborhood, velocity, density, fluid)
            .map_or_else(Mat3::zero, |(grad, moment)| moment.inverse().map_or(grad, |inverse| grad.matmul(inverse)))
    }
}
