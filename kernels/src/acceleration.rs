//! Accelerations (Algorithm 1, lines 14-15): pressure, viscosity and gravity.

use crate::cell_grid::{Neighborhood, Neighbors};
use crate::cross_viscosity::Newtonian;
use crate::density::pressure;
use crate::fluid::Fluid;
use crate::real::Real;
use crate::smoothing::SmoothingKernels;
use crate::topology::Open;
use crate::vec3::{SymTensor, Vec3};
use crate::view::{SymTensorView, Vec3View, Vec3ViewMut, View};

/// A discretisation of the viscous acceleration (1/rho) div tau. The operator is a type
/// parameter of the acceleration pass, chosen once per run.
pub trait ViscousOperator<R: Real>: Copy + Send + Sync {
    /// The operator's name in PTX kernel names (`acceleration_<NAME>_f32`).
    const NAME: &'static str;
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
        let s = &self.stress;
        SymTensor { xx: s.xx.at(i), yy: s.yy.at(i), zz: s.zz.at(i), xy: s.xy.at(i), xz: s.xz.at(i), yz: s.yz.at(i) }
            .scaled(R::ONE / (density * density))
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
/// [`crate::shear_viscosity`] it carries the Cross model: it discretises div(nu grad v), which
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

/// Acceleration of fluid particle `i` (m/s^2): pressure, Eq. (7), as an acceleration,
/// -(1/rho_i) sum_j m_j (p_i + p_j) / (2 rho_j) grad_i W (Müller 2003's force over rho_i; the
/// 1/2 is `fluid.pressure_pair_weight`), plus the viscous operator, plus gravity. Symmetric in
/// i and j: pair forces cancel.
#[inline(always)]
pub fn acceleration<R: Real, Op: ViscousOperator<R>, N: Neighbors>(
    i: usize,
    neighborhood: &N,
    density: &View<R>,
    fluid: &Fluid<R>,
    viscous: &Op,
) -> Vec3<R> {
    let rho_i = density.at(i);
    let p_i = pressure(rho_i, fluid);
    let own = viscous.own(i, rho_i);
    let mut pressure_sum = Vec3::zero();
    let mut viscous_sum = Vec3::zero();
    neighborhood.for_each_neighbor(i, fluid.kernels.h2, |j, r_ij, r2| {
        let rho_j = density.at(j);
        let grad_w = fluid.kernels.spiky_gradient(r_ij, r2);
        pressure_sum += grad_w * ((p_i + pressure(rho_j, fluid)) / rho_j);
        viscous_sum += viscous.pair(&own, j, rho_j, r_ij, r2, grad_w, &fluid.kernels);
    });
    pressure_sum * (-fluid.pressure_pair_weight * fluid.mass / rho_i) + viscous_sum * fluid.mass + fluid.gravity
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
