//! The paper's operator with hourglass control: Eq. (9) plus a pair force on the part of each
//! pair's velocity difference that the velocity gradients of Eq. (8) do not explain.
//!
//! Eq. (8) then (9) differentiate twice with first-derivative sums. On a lattice a velocity
//! that alternates from one particle layer to the next has zero gradient by Eq. (8), so it
//! costs no stress and nothing damps it: the zero-energy ("hourglass") mode of collocation
//! methods. The control term is Morris's Laplacian applied to the residual
//! e_ij = (v_j - v_i) - (grad v_i + grad v_j) / 2 · (x_j - x_i), after Ganzenmüller's
//! hourglass control for SPH (arXiv:1410.7221) in its velocity form ("A generalized
//! non-hourglass updated Lagrangian formulation for SPH solid dynamics", arXiv:2409.11474).
//! The residual vanishes for a linear velocity field and, by the trapezoid rule, is third
//! order in the spacing for a smooth one, so the continuum operator stays the paper's; the
//! alternating mode has no gradient, so it gets the full Laplacian's damping.

use super::laplacian_morris1997::morris_pair_weight;
use super::ViscousOperator;
use crate::cell_grid::{Neighborhood, Neighbors};
use crate::cross_viscosity::Rheology;
use crate::fluid::Fluid;
use crate::real::Real;
use crate::smoothing::SmoothingKernels;
use crate::topology::Open;
use crate::vec3::{Mat3, SymTensor, Vec3};
use crate::velocity_gradient::{rate_of_deformation, shear_rate, velocity_gradient};
use crate::view::{Mat3View, Mat3ViewMut, Vec3View, View, ViewMut};

/// Arguments of the velocity-gradient pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct VelocityGradientArgs<'a, R, Rh, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    pub rheology: Rh,
    /// Velocity the viscous terms read (m/s): see `leapfrog`.
    pub velocity: Vec3View<'a, R>,
    pub density: View<'a, R>,
    /// grad v, Eq. (8) (1/s).
    pub gradient: Mat3ViewMut<'a, R>,
    /// Kinematic viscosity nu(D), Eq. (2), (3) (m^2/s).
    pub viscosity: ViewMut<'a, R>,
}

/// The velocity-gradient pass for particle `i`: Eq. (8), and the viscosity at its shear rate
/// (boundary particles included: the acceleration pass reads theirs).
#[inline(always)]
pub fn velocity_gradient_pass<R: Real, Rh: Rheology<R>, N: Neighbors>(i: usize, a: &VelocityGradientArgs<R, Rh, N>) {
    let grad = velocity_gradient(i, &a.neighborhood, &a.velocity, &a.density, &a.fluid);
    let nu = a.rheology.viscosity(shear_rate(rate_of_deformation(grad)));
    // SAFETY: invocation i owns entry i.
    unsafe {
        a.gradient.write(i, grad.m);
        a.viscosity.write(i, nu);
    }
}

/// Eq. (9), sum_j m_j (tau_i / rho_i^2 + tau_j / rho_j^2) · grad_i W with tau = rho nu D, plus
/// `coefficient` times Morris's Laplacian of the hourglass residual e_ij (see the module docs),
/// sum_j m_j (nu_i / rho_j + nu_j / rho_i) / 2 e_ij F(r), whose pair weight is that of
/// [`MorrisViscosity`](super::laplacian_morris1997::MorrisViscosity), [`morris_pair_weight`]: symmetric,
/// so with e_ji = -e_ij pair forces cancel.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct HourglassControlledStress<'a, R> {
    /// The control's weight against Morris's Laplacian (dimensionless; 0 is the paper's operator).
    pub coefficient: R,
    /// Velocity the viscous terms read (m/s): see `leapfrog`.
    pub velocity: Vec3View<'a, R>,
    /// grad v (1/s), from [`velocity_gradient_pass`].
    pub gradient: Mat3View<'a, R>,
    /// nu(D) (m^2/s), from [`velocity_gradient_pass`].
    pub viscosity: View<'a, R>,
}

/// What the operator reads of particle i once.
#[derive(Clone, Copy)]
pub struct OwnGradient<R> {
    velocity: Vec3<R>,
    gradient: Mat3<R>,
    /// tau_i / rho_i^2 (Pa m^6/kg^2).
    stress_over_density2: SymTensor<R>,
    /// nu_i / 2 (m^2/s).
    half_viscosity: R,
    /// 1 / rho_i (m^3/kg).
    inverse_density: R,
}

impl<R: Real> HourglassControlledStress<'_, R> {
    #[inline(always)]
    fn gradient_at(&self, i: usize) -> Mat3<R> {
        Mat3 { m: self.gradient.at(i) }
    }
}

impl<R: Real> ViscousOperator<R> for HourglassControlledStress<'_, R> {
    const NAME: &'static str = "hourglass";
    type Own = OwnGradient<R>;
    #[inline(always)]
    fn own(&self, i: usize, density_i: R) -> OwnGradient<R> {
        let [x, y, z] = self.velocity.at(i);
        let gradient = self.gradient_at(i);
        let nu = self.viscosity.at(i);
        OwnGradient {
            velocity: Vec3::new(x, y, z),
            gradient,
            stress_over_density2: rate_of_deformation(gradient).scaled(nu / density_i),
            half_viscosity: nu * R::from_f64(0.5),
            inverse_density: R::ONE / density_i,
        }
    }
    #[inline(always)]
    fn pair(
        &self,
        own: &OwnGradient<R>,
        j: usize,
        density_j: R,
        r_ij: Vec3<R>,
        r2: R,
        grad_w: Vec3<R>,
        kernels: &SmoothingKernels<R>,
    ) -> Vec3<R> {
        let gradient_j = self.gradient_at(j);
        let nu_j = self.viscosity.at(j);
        let inv_rho_j = R::ONE / density_j;
        let stress = (own.stress_over_density2 + rate_of_deformation(gradient_j).scaled(nu_j * inv_rho_j)).dot(grad_w);
        let [x, y, z] = self.velocity.at(j);
        let residual = Vec3::new(x, y, z) - own.velocity + (own.gradient + gradient_j).dot(r_ij) * R::from_f64(0.5);
        let weight = morris_pair_weight(own.half_viscosity, own.inverse_density, nu_j, inv_rho_j);
        stress + residual * (self.coefficient * weight * kernels.morris_laplacian(r2))
    }
}
