//! Accelerations (Algorithm 1, lines 14-15): pressure, viscosity and gravity.

use crate::cell_grid::{Neighborhood, Neighbors};
use crate::density::pressure;
use crate::fluid::Fluid;
use crate::real::Real;
use crate::topology::Open;
use crate::vec3::Vec3;
use crate::view::{Vec3ViewMut, View};
use crate::viscosity::ViscousOperator;

/// Eq. (7), particle j's term of the pressure sum: (p_i + p_j) / rho_j grad_i W (1/(m^2 s^2));
/// [`pressure_acceleration`] turns the sum into an acceleration.
#[inline(always)]
pub fn pressure_pair<R: Real>(p_i: R, p_j: R, rho_j: R, grad_w: Vec3<R>) -> Vec3<R> {
    grad_w * ((p_i + p_j) / rho_j)
}

/// Eq. (7) as an acceleration (m/s^2), -(1/rho_i) sum_j m_j (p_i + p_j) / (2 rho_j) grad_i W,
/// from the sum of [`pressure_pair`] over j (Müller 2003's force over rho_i; the 1/2 is
/// `fluid.pressure_pair_weight`). Symmetric in i and j: pair forces cancel.
#[inline(always)]
pub fn pressure_acceleration<R: Real>(pressure_sum: Vec3<R>, rho_i: R, fluid: &Fluid<R>) -> Vec3<R> {
    pressure_sum * (-fluid.pressure_pair_weight * fluid.mass / rho_i)
}

/// Acceleration of fluid particle `i` (m/s^2): pressure, Eq. (7), plus the viscous operator,
/// plus gravity; gravity alone, without a neighbor loop, where pressure is solved apart (no
/// sound speed) and the operator adds nothing.
#[inline(always)]
pub fn acceleration<R: Real, Op: ViscousOperator<R>, N: Neighbors>(
    i: usize,
    neighborhood: &N,
    density: &View<R>,
    fluid: &Fluid<R>,
    viscous: &Op,
) -> Vec3<R> {
    if !Op::VISCOUS && fluid.sound_speed2 == R::ZERO {
        return fluid.gravity;
    }
    let rho_i = density.at(i);
    let p_i = pressure(rho_i, fluid);
    let own = viscous.own(i, rho_i);
    let mut pressure_sum = Vec3::zero();
    let mut viscous_sum = Vec3::zero();
    neighborhood.for_each_neighbor(i, fluid.kernels.h2, |j, r_ij, r2| {
        let rho_j = density.at(j);
        let grad_w = fluid.kernels.spiky_gradient(r_ij, r2);
        pressure_sum += pressure_pair(p_i, pressure(rho_j, fluid), rho_j, grad_w);
        viscous_sum += viscous.pair(&own, j, rho_j, r_ij, r2, grad_w, &fluid.kernels);
    });
    pressure_acceleration(pressure_sum, rho_i, fluid) + viscous_sum * fluid.mass + fluid.gravity
}

/// Arguments of the acceleration pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AccelerationArgs<'a, R, Op, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    pub viscous: Op,
    pub id: View<'a, u32>,
    pub density: View<'a, R>,
    pub acceleration: Vec3ViewMut<'a, R>,
}

/// The acceleration pass for particle `i`; fixed boundary particles get zero.
#[inline(always)]
pub fn acceleration_pass<R: Real, Op: ViscousOperator<R>, N: Neighbors>(i: usize, a: &AccelerationArgs<R, Op, N>) {
    let acc = if a.fluid.is_boundary(a.id.at(i)) {
        Vec3::zero()
    } else {
        acceleration(i, &a.neighborhood, &a.density, &a.fluid, &a.viscous)
    };
    // SAFETY: invocation i owns entry i.
    unsafe { a.acceleration.write(i, [acc.x, acc.y, acc.z]) };
}
