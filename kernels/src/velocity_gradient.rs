//! Velocity gradient, rate of deformation and shear rate (Eq. (8), (2)), which every viscous
//! pre-pass reads (Algorithm 1, line 10).

use crate::cell_grid::{GradientSum, Neighbors};
use crate::fluid::Fluid;
use crate::real::Real;
use crate::vec3::{Mat3, SymTensor, Vec3};
use crate::view::{Vec3View, View};

/// Velocity gradient, Eq. (8): grad v_i = sum_j (m_j / rho_j) (v_j - v_i) ⊗ grad_i W(x_ij)
/// (1/s), with `m[a][b] = d v_a / d x_b`. Zero, without the neighbor loop, away from fluid,
/// where every term is zero.
#[inline(always)]
pub fn velocity_gradient<R: Real, N: Neighbors>(
    i: usize,
    neighborhood: &N,
    velocity: &Vec3View<R>,
    density: &View<R>,
    fluid: &Fluid<R>,
) -> Mat3<R> {
    kernel_sums::<R, N, false, false>(i, neighborhood, velocity, density, fluid).map_or_else(Mat3::zero, |(grad, _)| grad)
}

/// Eq. (8)'s sum and, with `MOMENT`, its moment matrix sum_j (m_j / rho_j) (x_j - x_i) ⊗
/// grad_i W(x_ij) (dimensionless; the identity inside a lattice), in one neighbor loop; with
/// `OWN_DENSITY` each neighbor's volume is m_j / rho_i instead of m_j / rho_j. `None` away from
/// fluid, where every term is zero.
#[inline(always)]
pub(crate) fn kernel_sums<R: Real, N: Neighbors, const MOMENT: bool, const OWN_DENSITY: bool>(
    i: usize,
    neighborhood: &N,
    velocity: &Vec3View<R>,
    density: &View<R>,
    fluid: &Fluid<R>,
) -> Option<(Mat3<R>, Mat3<R>)> {
    if !neighborhood.near_fluid(i) {
        return None;
    }
    let [vx, vy, vz] = velocity.at(i);
    let vi = Vec3::new(vx, vy, vz);
    let own_volume_over_mass = if OWN_DENSITY { R::ONE / density.at(i) } else { R::ZERO };
    let mut sum = VelocityGradientSum::<R, OWN_DENSITY> { velocity, density, vi, own_volume_over_mass, grad: Mat3::zero() };
    let mut moment = Mat3::zero();
    if MOMENT {
        neighborhood.for_each_neighbor(i, fluid.kernels.h2, |j, r_ij, r2| {
            let grad_w = fluid.kernels.spiky_gradient(r_ij, r2);
            sum.add(j, grad_w);
            moment.add_outer(-r_ij * sum.volume_over_mass(j), grad_w);
        });
    } else {
        neighborhood.sum_spiky_gradients(i, &fluid.kernels, &mut sum);
    }
    Some((sum.grad.scaled(fluid.mass), moment.scaled(fluid.mass)))
}

/// Eq. (8)'s sum without the mass: sum_j (V_j / m_j) (v_j - v_i) ⊗ grad_i W(x_ij).
struct VelocityGradientSum<'v, 'a, R, const OWN_DENSITY: bool> {
    velocity: &'v Vec3View<'a, R>,
    density: &'v View<'a, R>,
    vi: Vec3<R>,
    own_volume_over_mass: R,
    grad: Mat3<R>,
}

impl<R: Real, const OWN_DENSITY: bool> VelocityGradientSum<'_, '_, R, OWN_DENSITY> {
    /// V_j / m_j (m^3/kg): 1 / rho_i at the own density, else 1 / rho_j.
    #[inline(always)]
    fn volume_over_mass(&self, j: usize) -> R {
        if OWN_DENSITY {
            self.own_volume_over_mass
        } else {
            R::ONE / self.density.at(j)
        }
    }
}

impl<R: Real, const OWN_DENSITY: bool> GradientSum<R> for VelocityGradientSum<'_, '_, R, OWN_DENSITY> {
    #[inline(always)]
    fn add(&mut self, j: usize, grad_w: Vec3<R>) {
        let [x, y, z] = self.velocity.at(j);
        self.grad.add_outer((Vec3::new(x, y, z) - self.vi) * self.volume_over_mass(j), grad_w);
    }
}

/// How a pass estimates the velocity gradient, fixed for a run.
pub trait GradientEstimate: Copy + Send + Sync + 'static {
    /// Empty for Eq. (8) as printed; otherwise the estimate's part of PTX entry names.
    const NAME: &'static str;
    /// The velocity gradient of particle `i` (1/s), `m[a][b] = d v_a / d x_b`.
    fn velocity_gradient<R: Real, N: Neighbors>(
        i: usize,
        neighborhood: &N,
        velocity: &Vec3View<R>,
        density: &View<R>,
        fluid: &Fluid<R>,
    ) -> Mat3<R>;
}

/// Eq. (8) as printed: [`velocity_gradient`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KernelSum;

impl GradientEstimate for KernelSum {
    const NAME: &'static str = "";
    #[inline(always)]
    fn velocity_gradient<R: Real, N: Neighbors>(
        i: usize,
        neighborhood: &N,
        velocity: &Vec3View<R>,
        density: &View<R>,
        fluid: &Fluid<R>,
    ) -> Mat3<R> {
        velocity_gradient(i, neighborhood, velocity, density, fluid)
    }
}

/// Eq. (8) with each neighbor's volume taken at the particle's own density, m_j / rho_i:
/// grad v_i = (1 / rho_i) sum_j m_j (v_j - v_i) ⊗ grad_i W(x_ij) (1/s). With it Eq. (9) is the
/// exact negative adjoint of the gradient: over any set of particles of equal mass, sum_i m
/// v_i · a_i = -sum_i (m / rho_i) tau_i : grad v_i, which is never positive, and the matrix
/// that maps velocities to the operator's accelerations is symmetric and negative semidefinite,
/// as a conjugate-gradient solve of implicit viscosity needs. Eq. (8) as printed, m_j / rho_j,
/// is neither where densities differ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OwnDensity;

impl GradientEstimate for OwnDensity {
    const NAME: &'static str = "own_density";
    #[inline(always)]
    fn velocity_gradient<R: Real, N: Neighbors>(
        i: usize,
        neighborhood: &N,
        velocity: &Vec3View<R>,
        density: &View<R>,
        fluid: &Fluid<R>,
    ) -> Mat3<R> {
        kernel_sums::<R, N, false, true>(i, neighborhood, velocity, density, fluid).map_or_else(Mat3::zero, |(grad, _)| grad)
    }
}

/// Rate-of-deformation tensor D = grad v + grad v^T (1/s), Sec. II.
#[inline(always)]
pub fn rate_of_deformation<R: Real>(velocity_gradient: Mat3<R>) -> SymTensor<R> {
    velocity_gradient.symmetric_sum()
}

/// Shear rate D = sqrt(tr(D·D) / 2) (1/s), Eq. (2). The printed "trace(D)^2" is the trace of
/// the squared tensor: the square of the trace vanishes for incompressible flow.
#[inline(always)]
pub fn shear_rate<R: Real>(deformation: SymTensor<R>) -> R {
    (deformation.double_contraction() * R::from_f64(0.5)).sqrt()
}
