//! The paper's viscous operator: the velocity gradient of Eq. (8), the shear rate of Eq. (2),
//! the Cross viscosity of Eq. (3) and the stress tau = rho nu D per particle (the pre-pass,
//! Algorithm 1, lines 10-11), then the stress divergence of Eq. (9) (the pair term).

use super::ViscousOperator;
use crate::cell_grid::{Neighborhood, Neighbors};
use crate::cross_viscosity::Rheology;
use crate::fluid::Fluid;
use crate::real::Real;
use crate::smoothing::SmoothingKernels;
use crate::topology::Open;
use crate::vec3::{SymTensor, Vec3};
use crate::velocity_gradient::{rate_of_deformation, shear_rate, GradientEstimate};
use crate::view::{SymTensorView, SymTensorViewMut, Vec3View, View};

/// Shear stress tau = rho nu(D) D (Pa), Eq. (2), with nu from `rheology` (Eq. (3)).
#[inline(always)]
pub fn stress<R: Real, Rh: Rheology<R>>(deformation: SymTensor<R>, density: R, rheology: &Rh) -> SymTensor<R> {
    deformation.scaled(density * rheology.viscosity(shear_rate(deformation)))
}

/// Arguments of the velocity-gradient-and-stress pass, with the velocity gradient estimated
/// by `G` (Eq. (8) as printed: `KernelSum`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct StressArgs<'a, R, Rh, G, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub gradient: G,
    pub fluid: Fluid<R>,
    pub rheology: Rh,
    /// Velocity the viscous terms read (m/s): see `leapfrog`.
    pub velocity: Vec3View<'a, R>,
    pub density: View<'a, R>,
    pub stress: SymTensorViewMut<'a, R>,
}

/// The stress pass for particle `i` (boundary particles included: Eq. (9) reads their stress).
#[inline(always)]
pub fn stress_pass<R: Real, Rh: Rheology<R>, G: GradientEstimate, N: Neighbors>(i: usize, a: &StressArgs<R, Rh, G, N>) {
    let grad = G::velocity_gradient(i, &a.neighborhood, &a.velocity, &a.density, &a.fluid);
    let tau = stress(rate_of_deformation(grad), a.density.at(i), &a.rheology);
    // SAFETY: invocation i owns entry i.
    unsafe { a.stress.write(i, tau) };
}

/// The paper's operator, Eq. (9): sum_j m_j (tau_i / rho_i^2 + tau_j / rho_j^2) · grad_i W,
/// with the stress of the previous pass. Symmetric in i and j, so it conserves momentum.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct StressDivergence<'a, R> {
    pub stress: SymTensorView<'a, R>,
}

impl<'a, R: Real> StressDivergence<'a, R> {
    #[inline(always)]
    fn stress_over_density2(&self, i: usize, density: R) -> SymTensor<R> {
        self.stress.at(i).scaled(R::ONE / (density * density))
    }
}

impl<R: Real> ViscousOperator<R> for StressDivergence<'_, R> {
    const NAME: &'static str = "stress";
    type Own = SymTensor<R>;
    #[inline(always)]
    fn own(&self, i: usize, density_i: R) -> SymTensor<R> {
        self.stress_over_density2(i, density_i)
    }
    #[inline(always)]
    fn pair(
        &self,
        own: &SymTensor<R>,
        j: usize,
        density_j: R,
        _r_ij: Vec3<R>,
        _r2: R,
        grad_w: Vec3<R>,
        _: &SmoothingKernels<R>,
    ) -> Vec3<R> {
        (*own + self.stress_over_density2(j, density_j)).dot(grad_w)
    }
}
