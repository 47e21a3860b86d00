//! Implicit viscosity: backward Euler on the paper's viscous operator, solved matrix-free by
//! conjugate gradients with a 3x3 block-Jacobi preconditioner, the solver design of Weiler,
//! Koschier, Brand and Bender, "A Physically Consistent Implicit Viscosity Solver for SPH
//! Fluids" (CGF 2018), on the operator of Andrade et al. 2014 (Eq. 8 with the own-density
//! volume, 2, 3, 9).
//!
//! Over a step the viscous acceleration is A v at the new velocity, so the half-step velocity
//! solves (I - dt A) v = v*, with v* the half-step velocity kicked by pressure and gravity
//! alone and dt leap-frog's kick. With Eq. (8) at the particle's own density
//! (`velocity_gradient::OwnDensity`) A is symmetric and negative semidefinite, so I - dt A is
//! symmetric positive definite for every dt, as conjugate gradients need. The viscosity is
//! lagged: each particle's nu is read once a step from the shear rate (Eq. 2, 3) of the solve's
//! first guess, v* plus the last step's viscous change, which leaves A linear. (v* alone
//! carries the step's kick from gravity up to the walls, a shear of order dt that moved a
//! steady Cross channel by 0.7 % at 30 times the explicit bound.) Boundary particles keep their velocity through the solve (at rest, or under
//! mirrored walls the ghost velocity of the step's start): their rows are the identity and
//! their entries of the residual and of the search direction stay zero, which keeps A
//! symmetric where mirrored ghosts solved with the fluid would not.
//!
//! The passes of one step, in order: the acceleration pass with [`PressureAndGravity`], then
//! [`predictor_pass`], [`lagged_viscosity_pass`], [`system_block_pass`]; [`implicit_stress_pass`],
//! [`system_product_pass`], [`cg_start_pass`] and [`dot_pass`] on v* (the residual the
//! tolerance is relative to), then the same on the first guess; per iteration
//! [`implicit_stress_pass`] and [`system_product_pass`] on the search direction, [`dot_pass`],
//! [`cg_step_pass`], [`dot_pass`], [`cg_direction_pass`]; last [`viscous_acceleration_pass`].

use super::ViscousOperator;
use crate::cell_grid::{GradientSum, Neighborhood, Neighbors};
use crate::cross_viscosity::Rheology;
use crate::fluid::Fluid;
use crate::real::Real;
use crate::smoothing::SmoothingKernels;
use crate::topology::Open;
use crate::vec3::{SymTensor, Vec3};
use crate::velocity_gradient::{rate_of_deformation, shear_rate, GradientEstimate, OwnDensity};
use crate::view::{SymTensorView, SymTensorViewMut, Vec3View, Vec3ViewMut, View, ViewMut};

/// Particles per range of [`dot_pass`]: each range is summed in index order by one thread and
/// the ranges in range order by the host, so a dot product is the same on every backend and
/// thread count.
pub const DOT_RANGE: usize = 256;

#[inline(always)]
fn vec3<R: Real>(v: [R; 3]) -> Vec3<R> {
    Vec3::new(v[0], v[1], v[2])
}

#[inline(always)]
fn write_vec3<R: Real>(view: &Vec3ViewMut<R>, i: usize, v: Vec3<R>) {
    // SAFETY: invocation i owns entry i of every view it writes.
    unsafe { view.write(i, [v.x, v.y, v.z]) };
}

/// The acceleration pass's operator when viscosity is solved apart: no viscous term, so the
/// pass gives pressure (Eq. 7) and gravity.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PressureAndGravity;

impl<R: Real> ViscousOperator<R> for PressureAndGravity {
    const NAME: &'static str = "pressure";
    const VISCOUS: bool = false;
    type Own = ();
    #[inline(always)]
    fn own(&self, _i: usize, _density_i: R) {}
    #[inline(always)]
    fn pair(
        &self,
        _: &(),
        _j: usize,
        _density_j: R,
        _r_ij: Vec3<R>,
        _r2: R,
        _grad_w: Vec3<R>,
        _: &SmoothingKernels<R>,
    ) -> Vec3<R> {
        Vec3::zero()
    }
}

/// Arguments of [`predictor_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PredictorArgs<'a, R> {
    pub fluid: Fluid<R>,
    /// Leap-frog's kick (s).
    pub kick_dt: R,
    pub id: View<'a, u32>,
    /// v_{n-1/2} (m/s).
    pub velocity_half: Vec3View<'a, R>,
    /// A boundary particle's velocity, which the solve keeps (m/s).
    pub velocity: Vec3View<'a, R>,
    /// Pressure and gravity (m/s^2).
    pub acceleration: Vec3View<'a, R>,
    /// The last step's viscous change of velocity, v - v* (m/s).
    pub viscous_change: Vec3View<'a, R>,
    /// v* out (m/s).
    pub predicted: Vec3ViewMut<'a, R>,
    /// The solve's first guess out (m/s).
    pub solution: Vec3ViewMut<'a, R>,
}

/// v* = v_{n-1/2} + dt (pressure + gravity) for fluid, a boundary particle's own velocity; the
/// first guess is v* plus the last step's viscous change, which a slowly varying flow repeats
/// (Weiler et al.'s warm start).
#[inline(always)]
pub fn predictor_pass<R: Real>(i: usize, a: &PredictorArgs<R>) {
    let (v, guess) = if a.fluid.is_boundary(a.id.at(i)) {
        let v = vec3(a.velocity.at(i));
        (v, v)
    } else {
        let v = vec3(a.velocity_half.at(i)) + vec3(a.acceleration.at(i)) * a.kick_dt;
        (v, v + vec3(a.viscous_change.at(i)))
    };
    write_vec3(&a.predicted, i, v);
    write_vec3(&a.solution, i, guess);
}

/// Arguments of [`lagged_viscosity_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct LaggedViscosityArgs<'a, R, Rh, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    pub rheology: Rh,
    /// The solve's first guess (m/s).
    pub velocity: Vec3View<'a, R>,
    pub density: View<'a, R>,
    /// nu (m^2/s) out.
    pub viscosity: ViewMut<'a, R>,
}

/// nu_i from the shear rate of the first guess (Eq. 8 at the own density, 2, 3), held for the
/// step's solve.
#[inline(always)]
pub fn lagged_viscosity_pass<R: Real, Rh: Rheology<R>, N: Neighbors>(i: usize, a: &LaggedViscosityArgs<R, Rh, N>) {
    let grad = OwnDensity::velocity_gradient(i, &a.neighborhood, &a.velocity, &a.density, &a.fluid);
    let nu = a.rheology.viscosity(shear_rate(rate_of_deformation(grad)));
    // SAFETY: invocation i owns entry i.
    unsafe { a.viscosity.write(i, nu) };
}

/// Arguments of [`implicit_stress_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ImplicitStressArgs<'a, R, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    /// The velocity field the operator is applied to (m/s).
    pub velocity: Vec3View<'a, R>,
    pub density: View<'a, R>,
    /// The lagged nu (m^2/s).
    pub viscosity: View<'a, R>,
    /// tau / rho^2 (m^5/(kg s^2)) out.
    pub stress: SymTensorViewMut<'a, R>,
}

/// tau_i / rho_i^2 = nu_i D_i / rho_i, with tau_i = rho_i nu_i D_i (Eq. 2) of `velocity`, Eq.
/// (8) at the own density and the lagged nu: linear in `velocity`. Eq. (9) reads the stress
/// only over rho^2, and the product reads each neighbor's 30 to 40 times a step: dividing once
/// here saves a division per pair there.
#[inline(always)]
pub fn implicit_stress_pass<R: Real, N: Neighbors>(i: usize, a: &ImplicitStressArgs<R, N>) {
    let grad = OwnDensity::velocity_gradient(i, &a.neighborhood, &a.velocity, &a.density, &a.fluid);
    let stress_over_density2 = rate_of_deformation(grad).scaled(a.viscosity.at(i) / a.density.at(i));
    // SAFETY: invocation i owns entry i.
    unsafe { a.stress.write(i, stress_over_density2) };
}

/// Arguments of [`system_block_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct SystemBlockArgs<'a, R, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    /// Leap-frog's kick (s).
    pub kick_dt: R,
    pub id: View<'a, u32>,
    pub density: View<'a, R>,
    /// The lagged nu (m^2/s).
    pub viscosity: View<'a, R>,
    /// The diagonal block of I - dt A out.
    pub block: SymTensorViewMut<'a, R>,
}

/// The 3x3 diagonal block of I - dt A at particle i, the block-Jacobi preconditioner. With
/// g_ij = grad_i W(x_ij) and s_i = sum_j g_ij, the velocity of i alone enters tau_i through
/// -(m / rho_i) s_i and each tau_j through -(m / rho_j) g_ij, so Eq. (9) gives
/// dA_i / dv_i = -m^2 (nu_i / rho_i^2) (|s_i|^2 I + s_i s_i^T)
///               - m^2 sum_j (nu_j / rho_j^2) (|g_ij|^2 I + g_ij g_ij^T),
/// negative semidefinite; a boundary particle's block is the identity.
#[inline(always)]
pub fn system_block_pass<R: Real, N: Neighbors>(i: usize, a: &SystemBlockArgs<R, N>) {
    let mut block = SymTensor { xx: R::ONE, yy: R::ONE, zz: R::ONE, xy: R::ZERO, xz: R::ZERO, yz: R::ZERO };
    if !a.fluid.is_boundary(a.id.at(i)) && a.neighborhood.near_fluid(i) {
        let mut sums = BlockSums { args: a, s: Vec3::zero(), pairs: SymTensor::zero() };
        a.neighborhood.sum_spiky_gradients(i, &a.fluid.kernels, &mut sums);
        let rho_i = a.density.at(i);
        let own = isotropic_plus_outer(sums.s).scaled(a.viscosity.at(i) / (rho_i * rho_i));
        let m = a.fluid.mass;
        block = block + (own + sums.pairs).scaled(a.kick_dt * m * m);
    }
    // SAFETY: invocation i owns entry i.
    unsafe { a.block.write(i, block) };
}

/// The sums of [`system_block_pass`]: s_i, and sum_j (nu_j / rho_j^2) (|g_ij|^2 I + g_ij g_ij^T).
struct BlockSums<'s, 'a, R, N> {
    args: &'s SystemBlockArgs<'a, R, N>,
    s: Vec3<R>,
    pairs: SymTensor<R>,
}

impl<R: Real, N> GradientSum<R> for BlockSums<'_, '_, R, N> {
    #[inline(always)]
    fn add(&mut self, j: usize, g: Vec3<R>) {
        self.s += g;
        let rho_j = self.args.density.at(j);
        self.pairs = self.pairs + isotropic_plus_outer(g).scaled(self.args.viscosity.at(j) / (rho_j * rho_j));
    }
}

/// |g|^2 I + g g^T.
#[inline(always)]
fn isotropic_plus_outer<R: Real>(g: Vec3<R>) -> SymTensor<R> {
    let n2 = g.norm2();
    let o = SymTensor::outer(g);
    SymTensor { xx: o.xx + n2, yy: o.yy + n2, zz: o.zz + n2, ..o }
}

/// Arguments of [`system_product_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct SystemProductArgs<'a, R, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    /// Leap-frog's kick (s).
    pub kick_dt: R,
    pub id: View<'a, u32>,
    /// tau / rho^2 of `velocity` from [`implicit_stress_pass`] (m^5/(kg s^2)).
    pub stress: SymTensorView<'a, R>,
    /// The velocity field multiplied (m/s).
    pub velocity: Vec3View<'a, R>,
    /// (I - dt A) velocity out, zero at boundary particles (m/s).
    pub product: Vec3ViewMut<'a, R>,
}

/// (I - dt A) v at fluid particle i, A v being Eq. (9) over the stress of v.
#[inline(always)]
pub fn system_product_pass<R: Real, N: Neighbors>(i: usize, a: &SystemProductArgs<R, N>) {
    let product = if a.fluid.is_boundary(a.id.at(i)) {
        Vec3::zero()
    } else {
        let mut sum = StressDivergence { args: a, own: a.stress.at(i), sum: Vec3::zero() };
        a.neighborhood.sum_spiky_gradients(i, &a.fluid.kernels, &mut sum);
        vec3(a.velocity.at(i)) - sum.sum * (a.fluid.mass * a.kick_dt)
    };
    write_vec3(&a.product, i, product);
}

/// The sum of [`system_product_pass`], Eq. (9) over m: sum_j (tau_i / rho_i^2 + tau_j / rho_j^2) . g_ij.
struct StressDivergence<'s, 'a, R, N> {
    args: &'s SystemProductArgs<'a, R, N>,
    own: SymTensor<R>,
    sum: Vec3<R>,
}

impl<R: Real, N> GradientSum<R> for StressDivergence<'_, '_, R, N> {
    #[inline(always)]
    fn add(&mut self, j: usize, g: Vec3<R>) {
        self.sum += (self.own + self.args.stress.at(j)).dot(g);
    }
}

/// z = B^-1 r with B a diagonal block of I - dt A, which is symmetric positive definite.
#[inline(always)]
fn precondition<R: Real>(block: SymTensor<R>, r: Vec3<R>) -> Vec3<R> {
    block.solve(r).unwrap_or(r)
}

/// Arguments of [`cg_start_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CgStartArgs<'a, R> {
    pub fluid: Fluid<R>,
    pub id: View<'a, u32>,
    /// v* (m/s), the right-hand side.
    pub predicted: Vec3View<'a, R>,
    /// (I - dt A) times the first guess (m/s).
    pub product: Vec3View<'a, R>,
    pub block: SymTensorView<'a, R>,
    pub residual: Vec3ViewMut<'a, R>,
    pub preconditioned: Vec3ViewMut<'a, R>,
    pub direction: Vec3ViewMut<'a, R>,
}

/// r = v* - (I - dt A) x, z = B^-1 r, p = z; zero at boundary particles.
#[inline(always)]
pub fn cg_start_pass<R: Real>(i: usize, a: &CgStartArgs<R>) {
    let (r, z) = if a.fluid.is_boundary(a.id.at(i)) {
        (Vec3::zero(), Vec3::zero())
    } else {
        let r = vec3(a.predicted.at(i)) - vec3(a.product.at(i));
        (r, precondition(a.block.at(i), r))
    };
    write_vec3(&a.residual, i, r);
    write_vec3(&a.preconditioned, i, z);
    write_vec3(&a.direction, i, z);
}

/// Arguments of [`cg_step_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CgStepArgs<'a, R> {
    /// alpha = (r . z) / (p . (I - dt A) p).
    pub alpha: R,
    pub direction: Vec3View<'a, R>,
    pub product: Vec3View<'a, R>,
    pub block: SymTensorView<'a, R>,
    pub solution: Vec3ViewMut<'a, R>,
    pub residual: Vec3ViewMut<'a, R>,
    pub preconditioned: Vec3ViewMut<'a, R>,
}

/// x += alpha p, r -= alpha (I - dt A) p, z = B^-1 r. Boundary entries of p and of the product
/// are zero, so their x stays and their r and z stay zero.
#[inline(always)]
pub fn cg_step_pass<R: Real>(i: usize, a: &CgStepArgs<R>) {
    let p = vec3(a.direction.at(i));
    let x = vec3(a.solution.at(i)) + p * a.alpha;
    let r = vec3(a.residual.at(i)) - vec3(a.product.at(i)) * a.alpha;
    write_vec3(&a.solution, i, x);
    write_vec3(&a.residual, i, r);
    write_vec3(&a.preconditioned, i, precondition(a.block.at(i), r));
}

/// Arguments of [`cg_direction_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CgDirectionArgs<'a, R> {
    /// beta = (r . z) new / (r . z) old.
    pub beta: R,
    pub preconditioned: Vec3View<'a, R>,
    pub direction: Vec3ViewMut<'a, R>,
}

/// p = z + beta p.
#[inline(always)]
pub fn cg_direction_pass<R: Real>(i: usize, a: &CgDirectionArgs<R>) {
    let p = vec3(a.preconditioned.at(i)) + vec3(a.direction.at(i)) * a.beta;
    write_vec3(&a.direction, i, p);
}

/// Arguments of [`viscous_acceleration_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ViscousAccelerationArgs<'a, R> {
    pub fluid: Fluid<R>,
    /// Leap-frog's kick (s).
    pub kick_dt: R,
    pub id: View<'a, u32>,
    pub predicted: Vec3View<'a, R>,
    pub solution: Vec3View<'a, R>,
    /// Pressure and gravity in, plus the implicit viscous acceleration out (m/s^2).
    pub acceleration: Vec3ViewMut<'a, R>,
    /// v - v* out, the next step's warm start (m/s).
    pub viscous_change: Vec3ViewMut<'a, R>,
}

/// a += (v - v*) / dt: leap-frog's kick then lands on the solved half-step velocity.
#[inline(always)]
pub fn viscous_acceleration_pass<R: Real>(i: usize, a: &ViscousAccelerationArgs<R>) {
    if a.fluid.is_boundary(a.id.at(i)) {
        return;
    }
    let change = vec3(a.solution.at(i)) - vec3(a.predicted.at(i));
    write_vec3(&a.viscous_change, i, change);
    write_vec3(&a.acceleration, i, vec3(a.acceleration.at(i)) + change * (R::ONE / a.kick_dt));
}

/// Arguments of [`dot_pass`]: two dot products over the same particles.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct DotArgs<'a, R> {
    pub a: Vec3View<'a, R>,
    pub b: Vec3View<'a, R>,
    pub c: Vec3View<'a, R>,
    pub d: Vec3View<'a, R>,
}

/// Range `r`'s parts of a . b and c . d over particles r DOT_RANGE .. min((r + 1) DOT_RANGE,
/// n), summed in f64 in index order, written to `out[r]`.
#[inline(always)]
pub fn dot_pass<R: Real>(r: usize, n: usize, a: &DotArgs<R>, out: ViewMut<[f64; 2]>) {
    let start = r * DOT_RANGE;
    let end = if start + DOT_RANGE < n { start + DOT_RANGE } else { n };
    let mut sums = [0.0f64; 2];
    for i in start..end {
        let (x, y, z, w) = (a.a.at(i), a.b.at(i), a.c.at(i), a.d.at(i));
        for k in 0..3 {
            sums[0] += x[k].to_f64() * y[k].to_f64();
            sums[1] += z[k].to_f64() * w[k].to_f64();
        }
    }
    // SAFETY: invocation r owns entry r.
    unsafe { out.write(r, sums) };
}
