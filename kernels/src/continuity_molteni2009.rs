//! Density from the continuity equation with a density diffusion term: the delta-SPH of
//! Molteni and Colagrossi, "A simple procedure to improve the pressure evaluation in
//! hydrodynamic context using the SPH" (Comput. Phys. Commun. 2009), as DualSPHysics runs it.
//!
//! The density sum of Eq. (5) lacks neighbors at a free surface: a thread five particles
//! across is mostly surface, so its summed density sits far below rho0 while the fluid is at
//! rest, and Eq. (6) turns that deficit into a tension that tears it (or, clamped, into no
//! pressure at all, so that the thread stretches by losing density instead of thinning).
//! Integrating d rho / dt = -rho div v instead starts every particle at rho0 and changes its
//! density only where the flow compresses or dilates it, so a free surface carries no spurious
//! tension and a stretching thread can hold the tension p = -mu dU/dz that thins it. Fixed
//! boundary particles keep the summed density of the paper (Sec. III-B).

use crate::cell_grid::{Neighborhood, Neighbors};
use crate::density::{boundary_density, DensityKernel};
use crate::fluid::Fluid;
use crate::real::Real;
use crate::topology::Open;
use crate::vec3::Vec3;
use crate::view::{Vec3View, View, ViewMut};

/// Arguments of the density rate pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ContinuityArgs<'a, R, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    /// delta h c (m^2/s): the diffusivity of the density diffusion term.
    pub diffusivity: R,
    pub id: View<'a, u32>,
    /// Velocity at the full step (m/s).
    pub velocity: Vec3View<'a, R>,
    /// Density (kg/m^3): read for fluid particles, written for fixed boundary particles.
    pub density: ViewMut<'a, R>,
    /// d rho / dt of fluid particles (kg/(m^3 s)).
    pub density_rate: ViewMut<'a, R>,
}

/// d rho_i / dt (kg/(m^3 s)) of fluid particle `i`: the continuity equation,
/// sum_j m_j (v_i - v_j) . grad_i W_ij, plus the diffusion term
/// delta h c sum_j 2 (rho_j - rho_i) (x_j - x_i) . grad_i W_ij / |x_ij|^2 m_j / rho_j over fluid
/// neighbors j (Molteni and Colagrossi 2009, Eq. (12)), which damps the particle-scale density
/// noise that the continuity equation alone lets grow. W is the spiky kernel whose gradient
/// Eq. (7) takes.
#[inline(always)]
pub fn density_rate<R: Real, N: Neighbors>(i: usize, a: &ContinuityArgs<R, N>) -> R {
    let rho_i = a.density.at(i);
    let [x, y, z] = a.velocity.at(i);
    let v_i = Vec3::new(x, y, z);
    let mut compression = R::ZERO;
    let mut diffusion = R::ZERO;
    a.neighborhood.for_each_neighbor(i, a.fluid.kernels.h2, |j, r_ij: Vec3<R>, r2| {
        if r2 == R::ZERO {
            return;
        }
        let grad_w = a.fluid.kernels.spiky_gradient(r_ij, r2);
        let [x, y, z] = a.velocity.at(j);
        compression += (v_i - Vec3::new(x, y, z)).dot(grad_w);
        if !a.fluid.is_boundary(a.id.at(j)) {
            let rho_j = a.density.at(j);
            diffusion += (rho_j - rho_i) * (-r_ij.dot(grad_w) / r2) / rho_j;
        }
    });
    a.fluid.mass * (compression + R::from_f64(2.0) * a.diffusivity * diffusion)
}

/// The density rate pass for particle `i`: fluid particles get their d rho / dt, fixed
/// boundary particles their density by [`boundary_density`] with kernel `K`. Race-free: fluid
/// particles read only fluid densities, which this pass does not write.
#[inline(always)]
pub fn continuity_pass<R: Real, K: DensityKernel, N: Neighbors>(i: usize, a: &ContinuityArgs<R, N>) {
    // SAFETY: invocation i owns entry i of both outputs.
    unsafe {
        if a.fluid.is_boundary(a.id.at(i)) {
            a.density.write(i, boundary_density::<R, K, N>(i, &a.neighborhood, &a.fluid));
        } else {
            a.density_rate.write(i, density_rate(i, a));
        }
    }
}

/// Arguments of the density integration pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct DensityIntegrationArgs<'a, R> {
    pub fluid: Fluid<R>,
    /// This step's dt (s).
    pub dt: R,
    pub id: View<'a, u32>,
    pub density_rate: View<'a, R>,
    pub density: ViewMut<'a, R>,
}

/// rho_{n+1} = rho_n + dt d rho_n / dt for fluid particle `i`, after the accelerations have read
/// rho_n.
#[inline(always)]
pub fn density_integration_pass<R: Real>(i: usize, a: &DensityIntegrationArgs<R>) {
    if a.fluid.is_boundary(a.id.at(i)) {
        return;
    }
    // SAFETY: invocation i owns entry i.
    unsafe { a.density.write(i, a.density.at(i) + a.dt * a.density_rate.at(i)) };
}
