//! Müller, Charypar and Gross 2003's viscosity: nu0 times the SPH Laplacian of velocity with
//! their viscosity kernel. The paper's Fig. 6 compares its operator with this one.

use super::ViscousOperator;
use crate::real::Real;
use crate::smoothing::SmoothingKernels;
use crate::vec3::Vec3;
use crate::view::Vec3View;

/// Müller et al. 2003's operator (the paper's Fig. 6 comparison): the SPH Laplacian of velocity
/// with the viscosity kernel, sum_j m_j mu0 (v_j - v_i) / (rho_i rho_j) lap W, mu0 = nu0 rho0.
/// Müller weighs a pair by nu0 / rho_j; at rest density the two agree, and this form is
/// symmetric in i and j, so the pair forces cancel and the operator conserves momentum where
/// densities differ (at a free surface). Newtonian only; needs no velocity-gradient or stress
/// pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct VelocityLaplacian<'a, R> {
    /// Dynamic viscosity at rest density, nu0 rho0 (Pa s).
    pub mu0: R,
    /// Velocity the viscous terms read (m/s): see `leapfrog`.
    pub velocity: Vec3View<'a, R>,
}

impl<R: Real> ViscousOperator<R> for VelocityLaplacian<'_, R> {
    const NAME: &'static str = "laplacian";
    /// v_i (m/s) and mu0 / rho_i (m^2/s).
    type Own = (Vec3<R>, R);
    #[inline(always)]
    fn own(&self, i: usize, density_i: R) -> (Vec3<R>, R) {
        let [x, y, z] = self.velocity.at(i);
        (Vec3::new(x, y, z), self.mu0 / density_i)
    }
    #[inline(always)]
    fn pair(
        &self,
        own: &(Vec3<R>, R),
        j: usize,
        density_j: R,
        _r_ij: Vec3<R>,
        r2: R,
        _grad_w: Vec3<R>,
        kernels: &SmoothingKernels<R>,
    ) -> Vec3<R> {
        let [x, y, z] = self.velocity.at(j);
        (Vec3::new(x, y, z) - own.0) * (own.1 * kernels.viscosity_laplacian(r2) / density_j)
    }
}
