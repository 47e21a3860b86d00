//! Morris, Fox and Zhu 1997's viscous operator, with a constant viscosity or, through the
//! shear-viscosity pre-pass, a per-particle one; and the same operator as the matrix of the
//! implicit viscosity solve (`implicit_weiler2018`): its products and diagonal blocks.
//!
//! The pre-pass: per-particle viscosity for Morris's operator with a shear-thinning fluid: nu_i = nu(D_i),
//! Eq. (3), at the shear rate D_i of Eq. (2) from the velocity gradient of Eq. (8).
//!
//! The paper's operator differentiates twice with first-derivative sums (Eq. (8), then (9)),
//! whose product ignores a velocity that alternates from one particle layer to the next.
//! Morris's Laplacian sees that mode; this pass lets it carry a shear-thinning viscosity too.

use super::ViscousOperator;
use crate::cell_grid::{Neighborhood, Neighbors};
use crate::cross_viscosity::{Newtonian, Rheology};
use crate::fluid::Fluid;
use crate::real::Real;
use crate::smoothing::SmoothingKernels;
use crate::topology::Open;
use crate::vec3::{SymTensor, Vec3};
use crate::velocity_gradient::{rate_of_deformation, shear_rate, velocity_gradient};
use crate::view::{SymTensorViewMut, Vec3View, Vec3ViewMut, View, ViewMut};

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

/// Where Morris's operator reads a particle's kinematic viscosity (m^2/s): the one constant
/// of a Newtonian fluid, or the array the shear-viscosity pass wrote.
pub trait ParticleViscosity<R: Real>: Copy + Send + Sync {
    /// The operator's name in PTX kernel names (`acceleration_<NAME>_f32`).
    const OPERATOR_NAME: &'static str;
    fn at(&self, i: usize) -> R;
}

impl<R: Real> ParticleViscosity<R> for Newtonian<R> {
    const OPERATOR_NAME: &'static str = "morris";
    #[inline(always)]
    fn at(&self, _i: usize) -> R {
        self.nu0
    }
}

impl<R: Real> ParticleViscosity<R> for View<'_, R> {
    const OPERATOR_NAME: &'static str = "morris_shear";
    #[inline(always)]
    fn at(&self, i: usize) -> R {
        View::at(self, i)
    }
}

/// Morris, Fox & Zhu 1997's operator: sum_j m_j (mu_i + mu_j) / (2 rho_i rho_j) (v_j - v_i) F(r)
/// with mu = rho nu, that is m_j (nu_i / rho_j + nu_j / rho_i) / 2, and Morris's Laplacian
/// weight F (`SmoothingKernels::morris_laplacian`). The pair weight ([`morris_pair_weight`]) is
/// symmetric in i and j, so pair forces cancel and every pair takes kinetic energy out, at
/// m^2 w_ij F |v_i - v_j|^2, whatever the densities: at a free surface, whose densities fall
/// short of rho0, (nu_i + nu_j) / (2 rho_j) would do neither. With nu from
/// [`shear_viscosity_pass`] it carries the Cross model: it discretises div(nu grad v), which
/// is (1/rho) div tau wherever nu varies only across the streamlines (every channel flow) and
/// leaves out grad nu · grad v^T elsewhere. Unlike Eq. (8) then (9) it has no odd-even null
/// mode, and unlike Müller's kernel it keeps its lattice calibration as layers slide past each
/// other.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct MorrisViscosity<'a, R, Nu> {
    /// Velocity the viscous terms read (m/s): see `leapfrog`.
    pub velocity: Vec3View<'a, R>,
    /// Kinematic viscosity (m^2/s).
    pub viscosity: Nu,
}

impl<R: Real, Nu: ParticleViscosity<R>> ViscousOperator<R> for MorrisViscosity<'_, R, Nu> {
    const NAME: &'static str = Nu::OPERATOR_NAME;
    /// Velocity (m/s), half the viscosity (m^2/s) and 1 / rho_i (m^3/kg).
    type Own = (Vec3<R>, R, R);
    #[inline(always)]
    fn own(&self, i: usize, density_i: R) -> (Vec3<R>, R, R) {
        let [x, y, z] = self.velocity.at(i);
        (Vec3::new(x, y, z), self.viscosity.at(i) * R::from_f64(0.5), R::ONE / density_i)
    }
    #[inline(always)]
    fn pair(
        &self,
        own: &(Vec3<R>, R, R),
        j: usize,
        density_j: R,
        _r_ij: Vec3<R>,
        r2: R,
        _grad_w: Vec3<R>,
        kernels: &SmoothingKernels<R>,
    ) -> Vec3<R> {
        let [x, y, z] = self.velocity.at(j);
        let weight = morris_pair_weight(own.1, own.2, self.viscosity.at(j), R::ONE / density_j);
        (Vec3::new(x, y, z) - own.0) * (weight * kernels.morris_laplacian(r2))
    }
}

/// Morris et al.'s pair weight (mu_i + mu_j) / (2 rho_i rho_j) with mu = rho nu, that is
/// (nu_i / rho_j + nu_j / rho_i) / 2 (m^5/(kg s)), from half of nu_i (m^2/s), 1 / rho_i
/// (m^3/kg), nu_j and 1 / rho_j.
#[inline(always)]
pub fn morris_pair_weight<R: Real>(half_viscosity_i: R, inverse_density_i: R, viscosity_j: R, inverse_density_j: R) -> R {
    half_viscosity_i * inverse_density_j + viscosity_j * R::from_f64(0.5) * inverse_density_i
}

/// Arguments of [`morris_system_block_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct MorrisSystemBlockArgs<'a, R, Nu, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    /// Leap-frog's kick (s).
    pub kick_dt: R,
    pub id: View<'a, u32>,
    pub density: View<'a, R>,
    /// The solve's kinematic viscosity (m^2/s), lagged for a shear-thinning fluid.
    pub viscosity: Nu,
    /// The diagonal block of I - dt A out.
    pub block: SymTensorViewMut<'a, R>,
}

/// The 3x3 diagonal block of I - dt A for Morris's operator, the implicit solve's
/// preconditioner (`implicit_weiler2018`). A v_i = m sum_j w_ij F_ij (v_j - v_i) with the pair
/// weight w and Laplacian weight F both symmetric and non-negative, so A is symmetric and
/// negative semidefinite, and its block at i is -m sum_j w_ij F_ij times the identity (F is 0
/// at j = i); a boundary particle's block is the identity.
#[inline(always)]
pub fn morris_system_block_pass<R: Real, Nu: ParticleViscosity<R>, N: Neighbors>(i: usize, a: &MorrisSystemBlockArgs<R, Nu, N>) {
    let mut diagonal = R::ONE;
    if !a.fluid.is_boundary(a.id.at(i)) && a.neighborhood.near_fluid(i) {
        let half_viscosity_i = a.viscosity.at(i) * R::from_f64(0.5);
        let inverse_density_i = R::ONE / a.density.at(i);
        let mut sum = R::ZERO;
        a.neighborhood.for_each_neighbor(i, a.fluid.kernels.h2, |j, _r_ij, r2| {
            let weight = morris_pair_weight(half_viscosity_i, inverse_density_i, a.viscosity.at(j), R::ONE / a.density.at(j));
            sum += weight * a.fluid.kernels.morris_laplacian(r2);
        });
        diagonal += a.kick_dt * a.fluid.mass * sum;
    }
    let block = SymTensor { xx: diagonal, yy: diagonal, zz: diagonal, xy: R::ZERO, xz: R::ZERO, yz: R::ZERO };
    // SAFETY: invocation i owns entry i.
    unsafe { a.block.write(i, block) };
}

/// Arguments of [`morris_system_product_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct MorrisSystemProductArgs<'a, R, Nu, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    /// Leap-frog's kick (s).
    pub kick_dt: R,
    pub id: View<'a, u32>,
    pub density: View<'a, R>,
    /// The operator over the velocity field multiplied (m/s) and the solve's viscosity.
    pub operator: MorrisViscosity<'a, R, Nu>,
    /// (I - dt A) velocity out, zero at boundary particles (m/s).
    pub product: Vec3ViewMut<'a, R>,
}

/// (I - dt A) v at fluid particle i, A v being Morris's operator ([`MorrisViscosity`]), one
/// neighbor pass.
#[inline(always)]
pub fn morris_system_product_pass<R: Real, Nu: ParticleViscosity<R>, N: Neighbors>(
    i: usize,
    a: &MorrisSystemProductArgs<R, Nu, N>,
) {
    let product = if a.fluid.is_boundary(a.id.at(i)) {
        Vec3::zero()
    } else {
        let own = a.operator.own(i, a.density.at(i));
        let mut sum = Vec3::zero();
        a.neighborhood.for_each_neighbor(i, a.fluid.kernels.h2, |j, r_ij, r2| {
            // Morris's pair term reads F(r), not the kernel gradient.
            sum += a.operator.pair(&own, j, a.density.at(j), r_ij, r2, Vec3::zero(), &a.fluid.kernels);
        });
        own.0 - sum * (a.fluid.mass * a.kick_dt)
    };
    // SAFETY: invocation i owns entry i.
    unsafe { a.product.write(i, [product.x, product.y, product.z]) };
}
