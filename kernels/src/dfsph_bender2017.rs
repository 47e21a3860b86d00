//! Divergence-free SPH: Bender and Koschier, "Divergence-Free SPH for Incompressible and Viscous
//! Fluids" (IEEE TVCG 2017; SCA 2015). Pressure is not an equation of state but the solution of
//! two constraints, each solved by a few Jacobi-style sweeps over per-particle factors:
//!
//! - the divergence solve makes the velocity field divergence free, D rho / Dt = 0 (Eq. 9), at
//!   the start of a step;
//! - the density solve, after gravity and viscosity, makes the density the step would end at
//!   the rest density (Eq. 5-8).
//!
//! Both read one predicted density change over the step, dt sum_j m_j (v_i - v_j) . grad W_ij,
//! with the spiky gradient of Eq. (7), and correct it with the pressure acceleration
//! a_i = -sum_j m_j (s_i + s_j) grad W_ij, the symmetric pressure gradient with each particle's
//! stiffness s_i = p_i / rho_i^2 (Bender's kappa_i / rho_i). The paper's walls are at rest;
//! their particles lie on the fluid's lattice and take the fluid's mass, so that Akinci et
//! al.'s boundary volumes are m / rho0.
//!
//! A wall particle pushes with the stiffness of the fluid particle beside it, as the fluid's
//! `wall_stiffness_share` says: once (share 0, s_j = 0 in the sum above, as in SPlisHSPlasH),
//! or mirrored (share 1, s_j = s_i, Akinci et al. 2012) with, in the density solve, the
//! hydrostatic head between the particle and the wall added (Band et al. 2018's extrapolated
//! boundary pressure). Pushing once, the layer on a floor reads about twice rho0 g depth;
//! mirrored, rho0 g depth. Either way the particle's motion against a wall counts (1 + share)
//! times in the predicted density change and the factor, so that the pressure acceleration
//! stays the exact negative adjoint of the prediction and the system the sweeps solve is
//! symmetric (mirrored in the force alone, a closed channel at rest grew noise from rounding).
//! Where the fluid stops at a wall, as the solves make it, the prediction is the same.
//!
//! Pressure pushes and never pulls on the summed density of Eq. (5): each sweep is a projected
//! Jacobi update, relaxed, that keeps every particle's summed stiffness at or above zero. A free
//! surface, whose summed density falls short of rho0, is never pulled back together, and a
//! dilating flow is left alone; a particle that an earlier update over-expanded sheds its
//! stiffness. On the continuity density, which has no free-surface deficit, the density solve
//! may pull ([`DensityErrorArgs::least_stiffness`]): a stretching viscous thread holds the
//! tension that thins it, and [`density_rate_pass`] integrates the density the solve predicted.
//! A sweep may also repeat a share of the last sweep's change ([`Sweep`]): Chebyshev's weights,
//! which the host picks, let the long pressure waves of a deep pool converge in fewer sweeps.
//!
//! The passes of one step, in order: [`factor_pass`]; on the half-step velocity
//! [`warm_start_pass`] and [`pressure_change_pass`], then per sweep [`divergence_error_pass`],
//! [`error_sum_pass`] and [`pressure_change_pass`]; the model's accelerations; then the same
//! with [`density_error_pass`] on the acceleration; with the continuity density,
//! [`density_rate_pass`].

use crate::cell_grid::{GradientSum, Neighborhood, Neighbors};
use crate::fluid::Fluid;
use crate::real::Real;
use crate::topology::Open;
use crate::vec3::Vec3;
use crate::view::{Vec3View, Vec3ViewMut, View, ViewMut};

/// Particles per range of [`error_sum_pass`]: each range is summed in index order by one thread
/// and the ranges in range order by the host, so a mean error is the same on every backend and
/// thread count.
pub const ERROR_RANGE: usize = 256;

#[inline(always)]
fn vec3<R: Real>(v: [R; 3]) -> Vec3<R> {
    Vec3::new(v[0], v[1], v[2])
}

/// Arguments of [`factor_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct FactorArgs<'a, R, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    pub id: View<'a, u32>,
    pub density: View<'a, R>,
    /// alpha_i (m^5/kg); 0 for walls.
    pub factor: ViewMut<'a, R>,
}

/// The DFSPH factor, Eq. (8): alpha_i = rho_i / (|sum_j m_j grad W_ij|^2 + sum_{j fluid}
/// |m_j grad W_ij|^2) (m^5/kg), which turns a density error into the stiffness that removes it
/// where the particle's neighbors hold still. Walls count in the first sum only, since they do
/// not move, (1 + `wall_stiffness_share`) times. A particle with no neighbors gets 0 and is
/// never corrected.
#[inline(always)]
pub fn factor_pass<R: Real, N: Neighbors>(i: usize, a: &FactorArgs<R, N>) {
    let mut factor = R::ZERO;
    if !a.fluid.is_boundary(a.id.at(i)) {
        let mut sums = FactorSums { args: a, sum: Vec3::zero(), squares: R::ZERO };
        a.neighborhood.sum_spiky_gradients(i, &a.fluid.kernels, &mut sums);
        let denominator = sums.sum.dot(sums.sum) + sums.squares;
        if denominator > R::ZERO {
            factor = a.density.at(i) / denominator;
        }
    }
    // SAFETY: invocation i owns entry i.
    unsafe { a.factor.write(i, factor) };
}

/// The sums of [`factor_pass`]: sum_j m_j grad W_ij, and sum_j |m_j grad W_ij|^2 over fluid.
struct FactorSums<'s, 'a, R, N> {
    args: &'s FactorArgs<'a, R, N>,
    sum: Vec3<R>,
    squares: R,
}

impl<R: Real, N> GradientSum<R> for FactorSums<'_, '_, R, N> {
    #[inline(always)]
    fn add(&mut self, j: usize, grad_w: Vec3<R>) {
        let grad = grad_w * self.args.fluid.mass;
        if self.args.fluid.is_boundary(self.args.id.at(j)) {
            self.sum += grad * (R::ONE + self.args.fluid.wall_stiffness_share);
        } else {
            self.sum += grad;
            self.squares += grad.dot(grad);
        }
    }
}

/// A velocity field the density change is predicted from (m/s).
trait VelocityField<R> {
    fn at(&self, j: usize) -> Vec3<R>;
}

/// v_{n-1/2}.
struct HalfStep<'a, R>(Vec3View<'a, R>);

impl<R: Real> VelocityField<R> for HalfStep<'_, R> {
    #[inline(always)]
    fn at(&self, j: usize) -> Vec3<R> {
        vec3(self.0.at(j))
    }
}

/// v_{n-1/2} + kick_dt a, the velocity the step would end at.
struct Kicked<'a, R> {
    velocity_half: Vec3View<'a, R>,
    acceleration: Vec3View<'a, R>,
    kick_dt: R,
}

impl<R: Real> VelocityField<R> for Kicked<'_, R> {
    #[inline(always)]
    fn at(&self, j: usize) -> Vec3<R> {
        vec3(self.velocity_half.at(j)) + vec3(self.acceleration.at(j)) * self.kick_dt
    }
}

/// The sums of [`density_change`]: sum_j (v_i - v_j) . grad W_ij, a wall's `wall_weight`
/// times, and the neighbors besides i.
struct DensityChange<'a, V, R> {
    velocity: V,
    i: usize,
    v_i: Vec3<R>,
    /// 1 + the fluid's wall stiffness share.
    wall_weight: R,
    id: View<'a, u32>,
    boundary_count: u32,
    change: R,
    neighbors: u32,
}

impl<R: Real, V: VelocityField<R>> GradientSum<R> for DensityChange<'_, V, R> {
    #[inline(always)]
    fn add(&mut self, j: usize, grad_w: Vec3<R>) {
        let change = (self.v_i - self.velocity.at(j)).dot(grad_w);
        // Walls pushing once weigh as the fluid does, and no id need be read.
        let wall = self.wall_weight > R::ONE && self.id.at(j) < self.boundary_count;
        self.change += if wall { change * self.wall_weight } else { change };
        self.neighbors += (j != self.i) as u32;
    }
}

/// dt sum_j m_j (v_i - v_j) . grad W_ij (kg/m^3), a wall's term (1 + the wall stiffness
/// share) times (see the module's walls): the density change over dt that velocity
/// `velocity` makes at particle `i`, and how many neighbors it has besides itself.
#[inline(always)]
fn density_change<R: Real, N: Neighbors, V: VelocityField<R>>(
    i: usize,
    neighborhood: &N,
    fluid: &Fluid<R>,
    id: View<u32>,
    dt: R,
    velocity: V,
) -> (R, u32) {
    let v_i = velocity.at(i);
    let mut sums = DensityChange {
        velocity,
        i,
        v_i,
        wall_weight: R::ONE + fluid.wall_stiffness_share,
        id,
        boundary_count: fluid.boundary_count,
        change: R::ZERO,
        neighbors: 0,
    };
    neighborhood.sum_spiky_gradients(i, &fluid.kernels, &mut sums);
    (sums.change * fluid.mass * dt, sums.neighbors)
}

/// Below this many neighbors (of 32 inside the fluid at h = 2 spacings) a particle takes no
/// part in the divergence solve, as in SPlisHSPlasH: at a thin thread's surface the predicted
/// divergence of a few neighbors is noise that the solve would turn into pressure, and a
/// falling thread 12 D long blew apart.
pub const DIVERGENCE_NEIGHBORS: u32 = 20;

/// The stiffness s_i = p_i / rho_i^2 (m^5/(kg s^2)) that removes density error `error`
/// (kg/m^3) over a step that drifts by `dt` on a velocity kicked over `kick_dt` (s).
#[inline(always)]
fn stiffness<R: Real>(error: R, factor: R, density: R, dt: R, kick_dt: R) -> R {
    error * factor / (density * dt * kick_dt)
}

/// One projected Jacobi update of a particle whose density would change by `excess` (kg/m^3)
/// over the step, which stiffness `removing` would remove, whose stiffness applied so far is
/// `applied` and whose last sweep changed it by `last`: the stiffness change `sweep` makes of
/// them, held so that the particle's stiffness stays at or above `least` (0: pressure pushes,
/// never pulls), and the part of the excess that violates the constraint (kg/m^3): a
/// compression, or an expansion where the particle's stiffness is above `least`.
///
/// Projection rather than a clamped error is what lets a warm start work: a particle that the
/// last step's stiffness now over-expands sheds it instead of keeping it.
#[inline(always)]
fn projected<R: Real>(excess: R, removing: R, sweep: Sweep<R>, last: R, applied: R, least: R) -> (R, R) {
    let change = (sweep.relaxation * removing + sweep.momentum * last).max(least - applied);
    let violation = if excess > R::ZERO || applied > least { excess.abs() } else { R::ZERO };
    (violation, change)
}

/// How a sweep updates the stiffness: `relaxation` times the Jacobi update plus `momentum`
/// times the change the last sweep applied; Chebyshev's semi-iteration (Wang 2015) with weight
/// omega takes omega times the plain relaxation and a momentum of omega - 1.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct Sweep<R> {
    /// The share of the stiffness that removes the error which a sweep applies (above 0).
    pub relaxation: R,
    /// The share of the last sweep's stiffness change that this sweep repeats (0 to 1).
    pub momentum: R,
}

/// Arguments of [`divergence_error_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct DivergenceErrorArgs<'a, R, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    /// How the sweep updates the stiffness.
    pub sweep: Sweep<R>,
    /// The step's drift (s).
    pub dt: R,
    /// The step's kick (s), over which a stiffness acts.
    pub kick_dt: R,
    pub id: View<'a, u32>,
    pub density: View<'a, R>,
    pub factor: View<'a, R>,
    /// v_{n-1/2} (m/s), the velocity the divergence solve corrects; walls' at rest.
    pub velocity_half: Vec3View<'a, R>,
    /// The stiffness applied so far in this solve (m^5/(kg s^2)).
    pub stiffness_sum: View<'a, R>,
    /// In, the change of s_i the last sweep applied; out, the change this sweep applies
    /// (m^5/(kg s^2)); 0 for walls.
    pub stiffness: ViewMut<'a, R>,
    /// The part of dt D rho_i / Dt that violates the constraint (kg/m^3): a compression, or an
    /// expansion where the particle still pushes; 0 for walls.
    pub error: ViewMut<'a, R>,
}

/// The divergence error of fluid particle `i`, Eq. (9): the density change over dt that its
/// velocity field makes, and the stiffness change that removes it. A particle without a factor
/// (walls, fluid whose motion is imposed, a lone droplet) has neither; one with fewer than
/// [`DIVERGENCE_NEIGHBORS`] neighbors sheds its stiffness and has no error.
#[inline(always)]
pub fn divergence_error_pass<R: Real, N: Neighbors>(i: usize, a: &DivergenceErrorArgs<R, N>) {
    let (mut error, mut s) = (R::ZERO, R::ZERO);
    let factor = a.factor.at(i);
    if factor > R::ZERO {
        let (change, neighbors) = density_change(i, &a.neighborhood, &a.fluid, a.id, a.dt, HalfStep(a.velocity_half));
        let applied = a.stiffness_sum.at(i);
        (error, s) = if neighbors < DIVERGENCE_NEIGHBORS {
            (R::ZERO, -applied)
        } else {
            let removing = stiffness(change, factor, a.density.at(i), a.dt, a.kick_dt);
            projected(change, removing, a.sweep, a.stiffness.at(i), applied, R::ZERO)
        };
    }
    // SAFETY: invocation i owns entry i of both outputs.
    unsafe {
        a.error.write(i, error);
        a.stiffness.write(i, s);
    }
}

/// Arguments of [`density_error_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct DensityErrorArgs<'a, R, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    /// How the sweep updates the stiffness.
    pub sweep: Sweep<R>,
    /// The step's drift (s).
    pub dt: R,
    /// The step's kick (s).
    pub kick_dt: R,
    pub id: View<'a, u32>,
    pub density: View<'a, R>,
    pub factor: View<'a, R>,
    /// v_{n-1/2} (m/s).
    pub velocity_half: Vec3View<'a, R>,
    /// The step's acceleration so far (m/s^2): v_{n+1/2} = v_{n-1/2} + kick_dt a.
    pub acceleration: Vec3View<'a, R>,
    /// The least stiffness the solve may sum to (m^5/(kg s^2)): 0 on the summed density, where
    /// pressure only pushes; minus infinity on the continuity density, where it may pull.
    pub least_stiffness: R,
    /// The stiffness applied so far in this solve (m^5/(kg s^2)).
    pub stiffness_sum: View<'a, R>,
    /// In, the change of s_i the last sweep applied; out, the change this sweep applies
    /// (m^5/(kg s^2)); 0 for walls.
    pub stiffness: ViewMut<'a, R>,
    /// The part of rho_i + dt D rho_i / Dt - rho0 that violates the constraint (kg/m^3): an
    /// excess, or a deficit where the particle still pushes; 0 for walls.
    pub error: ViewMut<'a, R>,
}

/// The density error of fluid particle `i`, Eq. (5)-(6): by how much the density it would end
/// the step at exceeds rho0, and the stiffness that removes it; none without a factor.
#[inline(always)]
pub fn density_error_pass<R: Real, N: Neighbors>(i: usize, a: &DensityErrorArgs<R, N>) {
    let (mut error, mut s) = (R::ZERO, R::ZERO);
    let factor = a.factor.at(i);
    if factor > R::ZERO {
        let velocity = Kicked { velocity_half: a.velocity_half, acceleration: a.acceleration, kick_dt: a.kick_dt };
        let rho = a.density.at(i);
        let excess = rho + density_change(i, &a.neighborhood, &a.fluid, a.id, a.dt, velocity).0 - a.fluid.rest_density;
        let removing = stiffness(excess, factor, rho, a.dt, a.kick_dt);
        (error, s) = projected(excess, removing, a.sweep, a.stiffness.at(i), a.stiffness_sum.at(i), a.least_stiffness);
    }
    // SAFETY: invocation i owns entry i of both outputs.
    unsafe {
        a.error.write(i, error);
        a.stiffness.write(i, s);
    }
}

/// Arguments of [`density_rate_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct DensityRateArgs<'a, R, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    /// The step's kick (s).
    pub kick_dt: R,
    pub id: View<'a, u32>,
    pub factor: View<'a, R>,
    /// v_{n-1/2} (m/s).
    pub velocity_half: Vec3View<'a, R>,
    /// The step's acceleration, the density solve's included (m/s^2).
    pub acceleration: Vec3View<'a, R>,
    /// d rho / dt of fluid particles out (kg/(m^3 s)).
    pub density_rate: ViewMut<'a, R>,
}

/// The continuity equation's d rho_i / dt (kg/(m^3 s)) over the step as the density solve
/// predicts it, sum_j m_j (v_i - v_j) . grad W_ij on the velocity the step ends at,
/// v_{n-1/2} + kick_dt a, at the step's positions, a wall's term weighted as in the solve:
/// integrated over dt it gives each particle the density the solve drove to rho0, where the
/// continuity equation on the full-step velocity would drift from it step by step. 0 for a
/// fluid particle without a factor: inside a nozzle's tube (delivered at rho0, its motion
/// imposed), or a lone droplet. Walls, whose density is summed, are left as they are.
#[inline(always)]
pub fn density_rate_pass<R: Real, N: Neighbors>(i: usize, a: &DensityRateArgs<R, N>) {
    if a.fluid.is_boundary(a.id.at(i)) {
        return;
    }
    let mut rate = R::ZERO;
    if a.factor.at(i) > R::ZERO {
        let velocity = Kicked { velocity_half: a.velocity_half, acceleration: a.acceleration, kick_dt: a.kick_dt };
        rate = density_change(i, &a.neighborhood, &a.fluid, a.id, R::ONE, velocity).0;
    }
    // SAFETY: invocation i owns entry i.
    unsafe { a.density_rate.write(i, rate) };
}

/// Arguments of [`pressure_change_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PressureChangeArgs<'a, R, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    pub id: View<'a, u32>,
    pub density: View<'a, R>,
    pub stiffness: View<'a, R>,
    /// Times the walls' hydrostatic head that this application adds: the fluid's
    /// `wall_stiffness_share` once per density solve, 0 otherwise.
    pub wall_head: R,
    /// Times the pressure acceleration added to `target`: the kick (s) where it is a velocity,
    /// 1 where it is an acceleration.
    pub scale: R,
    /// What the pressure acceleration changes: each fluid particle's entry.
    pub target: Vec3ViewMut<'a, R>,
    /// Each fluid particle's stiffness summed over the solve (m^5/(kg s^2)).
    pub stiffness_sum: ViewMut<'a, R>,
}

/// Adds `scale` times the pressure acceleration of Eq. (7) in stiffness form,
/// -sum_j m_j (s_i + s_j) grad W_ij (m/s^2), to fluid particle `i`'s entry of `target`. A
/// wall's stiffness is the fluid's `wall_stiffness_share` of the particle's own, plus
/// `wall_head` times the hydrostatic head between them, rho0 g . (x_j - x_i) / rho_i^2.
#[inline(always)]
pub fn pressure_change_pass<R: Real, N: Neighbors>(i: usize, a: &PressureChangeArgs<R, N>) {
    if a.fluid.is_boundary(a.id.at(i)) {
        return;
    }
    let s_i = a.stiffness.at(i);
    let s_wall = a.fluid.wall_stiffness_share * s_i;
    let mut sum = PressureSum { args: a, s_i, s_wall, acceleration: Vec3::zero() };
    a.neighborhood.sum_spiky_gradients(i, &a.fluid.kernels, &mut sum);
    let mut acceleration = sum.acceleration;
    if a.wall_head > R::ZERO {
        // Apart from the sum above, which the sweeps run without a head: there the wall term
        // needs no separation and the loop stays as lean as the fluid's.
        let rho_i = a.density.at(i);
        let head = a.fluid.gravity * (a.wall_head * a.fluid.rest_density / (rho_i * rho_i));
        a.neighborhood.for_each_neighbor(i, a.fluid.kernels.h2, |j, r_ij, r2| {
            if a.fluid.is_boundary(a.id.at(j)) {
                acceleration += a.fluid.kernels.spiky_gradient(r_ij, r2) * head.dot(r_ij);
            }
        });
    }
    let change = acceleration * (a.fluid.mass * a.scale);
    let t = vec3(a.target.at(i)) + change;
    // SAFETY: invocation i owns entry i of both outputs.
    unsafe {
        a.target.write(i, [t.x, t.y, t.z]);
        a.stiffness_sum.write(i, a.stiffness_sum.at(i) + s_i);
    }
}

/// The sum of [`pressure_change_pass`] without the walls' head: -sum_j (s_i + s_j) grad W_ij.
struct PressureSum<'s, 'a, R, N> {
    args: &'s PressureChangeArgs<'a, R, N>,
    s_i: R,
    /// A wall's stiffness.
    s_wall: R,
    acceleration: Vec3<R>,
}

impl<R: Real, N> GradientSum<R> for PressureSum<'_, '_, R, N> {
    #[inline(always)]
    fn add(&mut self, j: usize, grad_w: Vec3<R>) {
        let a = self.args;
        let s_j = if a.fluid.is_boundary(a.id.at(j)) { self.s_wall } else { a.stiffness.at(j) };
        self.acceleration = self.acceleration - grad_w * (self.s_i + s_j);
    }
}

/// Arguments of [`warm_start_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct WarmStartArgs<'a, R> {
    /// The share of the last step's stiffness sum that the solve starts from (0 to 1).
    pub share: R,
    /// The last step's stiffness sum of this solve in, 0 out (m^5/(kg s^2)).
    pub stiffness_sum: ViewMut<'a, R>,
    /// The stiffness the solve applies first.
    pub stiffness: ViewMut<'a, R>,
}

/// The warm start of a solve (Bender and Koschier 2017, Sec. 4.3): particle `i` starts from a
/// share of the stiffness its last step summed, where the last step's pressure is the best
/// guess at this one's. The sum then starts again from what is applied.
#[inline(always)]
pub fn warm_start_pass<R: Real>(i: usize, a: &WarmStartArgs<R>) {
    let s = a.share * a.stiffness_sum.at(i);
    // SAFETY: invocation i owns entry i of both outputs.
    unsafe {
        a.stiffness.write(i, s);
        a.stiffness_sum.write(i, R::ZERO);
    }
}

/// Arguments of [`error_sum_pass`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ErrorSumArgs<'a, R> {
    pub fluid: Fluid<R>,
    pub id: View<'a, u32>,
    pub error: View<'a, R>,
}

/// Range `r`'s sum of the error and count of fluid particles over particles r ERROR_RANGE ..
/// min((r + 1) ERROR_RANGE, n), in f64 in index order, written to `out[r]`.
#[inline(always)]
pub fn error_sum_pass<R: Real>(r: usize, n: usize, a: &ErrorSumArgs<R>, out: ViewMut<[f64; 2]>) {
    let start = r * ERROR_RANGE;
    let end = if start + ERROR_RANGE < n { start + ERROR_RANGE } else { n };
    let mut sums = [0.0f64; 2];
    for i in start..end {
        if !a.fluid.is_boundary(a.id.at(i)) {
            sums[0] += a.error.at(i).to_f64();
            sums[1] += 1.0;
        }
    }
    // SAFETY: invocation r owns entry r.
    unsafe { out.write(r, sums) };
}

/// The pressure of fluid particle `i` in a solved run (Pa), as frames and validation read it:
/// the SPH interpolant sum_j V_j p_j W_ij / sum_j V_j W_ij (poly6, V_j = m / rho_j) of the
/// solved pressures p_j = rho_j^2 (s_j summed over both solves). Walls that mirror the
/// stiffness take part with the pressure the density solve gives them, the particle's own plus
/// the hydrostatic head; walls that push with it once carry none of their own and are left out.
/// On a lattice the symmetric pressure gradient cannot see a pressure that alternates layer by
/// layer, so the solved values carry such a mode wherever a free surface pins one set of
/// layers (a resting tank 10 layers deep: 0.05 of rho0 g D); the interpolant averages it out
/// as the gradient does.
#[inline(always)]
pub fn pressure_field<R: Real, N: Neighbors>(
    i: usize,
    neighborhood: &N,
    fluid: &Fluid<R>,
    id: View<u32>,
    density: View<R>,
    stiffness_sums: [View<R>; 2],
) -> R {
    let solved = |j: usize| {
        let rho = density.at(j);
        rho * rho * (stiffness_sums[0].at(j) + stiffness_sums[1].at(j))
    };
    let p_i = solved(i);
    let mirrored = fluid.wall_stiffness_share > R::ZERO;
    let head = fluid.gravity * fluid.rest_density;
    let wall_volume = fluid.mass / fluid.rest_density;
    let (mut weighted, mut weights) = (R::ZERO, R::ZERO);
    neighborhood.for_each_neighbor(i, fluid.kernels.h2, |j, r_ij, r2| {
        let (p_j, volume) = if !fluid.is_boundary(id.at(j)) {
            (solved(j), fluid.mass / density.at(j))
        } else if mirrored {
            (p_i * fluid.wall_stiffness_share - head.dot(r_ij), wall_volume)
        } else {
            return;
        };
        let w = fluid.kernels.poly6(r2) * volume;
        weighted += w * p_j;
        weights += w;
    });
    if weights > R::ZERO {
        (weighted / weights).max(R::ZERO)
    } else {
        p_i
    }
}
