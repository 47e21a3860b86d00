//! The viscous term (1/rho) div tau of Algorithm 1, line 15: one file per operator, named after
//! its source, each with its pre-pass (what it computes per particle before the acceleration
//! pass) and its pair term. The operator is a type parameter of the acceleration pass, chosen
//! once per run.
//!
//! - [`stress_andrade2014`]: the paper's operator, Eq. (8), (2), (3), then (9).
//! - [`laplacian_muller2003`]: Müller et al. 2003's Laplacian of velocity (Newtonian).
//! - [`laplacian_morris1997`]: Morris, Fox & Zhu 1997's Laplacian, Newtonian or with a
//!   per-particle Cross viscosity.
//! - [`hourglass_ganzenmuller2015`]: the paper's operator with hourglass control.
//! - [`implicit_weiler2018`]: the paper's operator solved implicitly (backward Euler, conjugate
//!   gradients), so that viscosity does not bound the time step.

use crate::real::Real;
use crate::smoothing::SmoothingKernels;
use crate::vec3::Vec3;

pub mod hourglass_ganzenmuller2015;
pub mod implicit_weiler2018;
pub mod laplacian_morris1997;
pub mod laplacian_muller2003;
pub mod stress_andrade2014;

/// A discretisation of the viscous acceleration (1/rho) div tau. The operator is a type
/// parameter of the acceleration pass, chosen once per run.
pub trait ViscousOperator<R: Real>: Copy + Send + Sync {
    /// The operator's name in PTX kernel names (`acceleration_<NAME>_f32`).
    const NAME: &'static str;
    /// Whether it adds anything: an operator that does not, and pressure that is solved
    /// elsewhere (no sound speed), leave the acceleration pass gravity alone.
    const VISCOUS: bool = true;
    /// What the operator reads of particle i once, before its neighbor loop.
    type Own: Copy;
    fn own(&self, i: usize, density_i: R) -> Self::Own;
    /// Particle j's contribution to particle i's viscous acceleration divided by m_j
    /// (m/s^2 per kg), for `r_ij = x_i - x_j` (m), `r2` its square and `grad_w` the spiky
    /// gradient there.
    #[allow(clippy::too_many_arguments)]
    fn pair(
        &self,
        own: &Self::Own,
        j: usize,
        density_j: R,
        r_ij: Vec3<R>,
        r2: R,
        grad_w: Vec3<R>,
        kernels: &SmoothingKernels<R>,
    ) -> Vec3<R>;
}
