//! Particle shifting: each step moves fluid particles a little down the gradient of their own
//! concentration, so that they stay evenly spread where the flow would order them into
//! layers, pairs and gaps. Fickian shifting of Lind, Xu, Stansby and Rogers (J. Comput. Phys.
//! 2012) with the anti-clumping weight and the free-surface projection of the delta-plus-SPH of
//! Sun, Colagrossi, Marrone and Zhang, "The delta-plus-SPH model: simple procedures for a
//! further improvement of the SPH scheme" (Comput. Methods Appl. Mech. Engrg. 2017), Eq. (28)-(30).
//!
//! A thread stretching as it falls moves its particles apart along its axis and together across
//! it, affinely: the layers in which an inlet injected the fluid never rearrange, their gaps
//! outgrow the support radius, and the thread parts into pairs of layers that fall freely
//! (docs/validation.md). Shifting lets particles move into those gaps.

use crate::cell_grid::Neighbors;
use crate::fluid::Fluid;
use crate::real::Real;
use crate::topology::{Open, Topology};
use crate::vec3::Vec3;
use crate::view::{Vec3View, Vec3ViewMut, View};

/// A run's shifting constants.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct Shifting<R> {
    /// A h (m): the scene's coefficient A times the support radius, so that a particle moving
    /// at |v| shifts by A h |v| dt grad C in a step, Lind et al.'s diffusion with the
    /// coefficient of Skillen et al. (2013).
    pub coefficient: R,
    /// 1 / W(spacing) with the spiky kernel (m^3): the anti-clumping weight's reference.
    pub inverse_spacing_weight: R,
    /// Below this divergence of position (3 inside the fluid) a particle is near a free
    /// surface and shifts only along it.
    pub surface_divergence: R,
    /// The longest shift of a step (m): [`LARGEST_SHIFT_SPACINGS`] particle spacings.
    pub largest_shift: R,
}

/// Arguments of the pass that computes each fluid particle's shift.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ShiftingArgs<'a, R, N> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    pub shifting: Shifting<R>,
    /// This step's dt (s).
    pub dt: R,
    pub id: View<'a, u32>,
    /// Velocity at the full step (m/s).
    pub velocity: Vec3View<'a, R>,
    /// This step's shift of each fluid particle (m).
    pub shift: Vec3ViewMut<'a, R>,
}

/// Sun et al.'s anti-clumping weight, R = 0.2 and n = 4 in their Eq. (28): pairs closer than the
/// spacing push each other apart harder than the concentration gradient alone would.
const CLUMPING_WEIGHT: f64 = 0.2;

/// The largest step of the diffusion, A h |v| dt, over h^2: a particle 0.3 spacings off its
/// lattice site has a concentration gradient of about 28 times its offset over h^2, so that at
/// this cap its shift undoes 0.9 of the offset and never overshoots it. The cap binds only
/// where |v| dt exceeds about h / 64 at A = 2: not under Eq. (10)'s viscous bound.
const LARGEST_DIFFUSION: f64 = 1.0 / 32.0;

/// The longest shift of a step, in particle spacings. The anti-clumping weight grows as
/// (W_ij / W(dx))^4 as a pair closes (14 times the plain gradient at 0.58 spacings, 820 at
/// coincidence), so where the diffusion cap binds, as it does at the CFL step of divergence-free
/// pressure, a particle almost on top of another would be thrown several spacings: one crossed a
/// jet's plate in two steps. A quarter spacing still parts a close pair within a step or two
/// and cannot carry a particle through a layer of its neighbors; under Eq. (10)'s bound it does
/// not bind (the shipped Newtonian jet's frames to 0.3 s are unchanged by it).
pub const LARGEST_SHIFT_SPACINGS: f64 = 0.25;

/// The shift of fluid particle `i` (m): -A h |v_i| dt sum_j V_j (1 + 0.2 (W_ij / W(dx))^4)
/// grad_i W_ij over every neighbor j, walls included so that no particle is shifted into a
/// wall, V_j = m / rho0 (Sun et al. 2017, Eq. (28)); near a free surface (divergence of
/// position, -sum_j V_j x_ij . grad_i W_ij, below `surface_divergence`) only its component
/// along the surface, whose normal is the plain concentration gradient's (Eq. (29)): the
/// concentration there falls because the fluid ends, not because particles bunch up. A h |v_i|
/// dt is capped at h^2 / 32 and the shift's length at `largest_shift`.
#[inline(always)]
pub fn particle_shift<R: Real, N: Neighbors>(i: usize, a: &ShiftingArgs<R, N>) -> Vec3<R> {
    let mut concentration_gradient = Vec3::zero();
    let mut shifting_gradient = Vec3::zero();
    let mut position_divergence = R::ZERO;
    let kernels = a.fluid.kernels;
    a.neighborhood.for_each_neighbor(i, kernels.h2, |_, r_ij: Vec3<R>, r2| {
        if r2 == R::ZERO {
            return;
        }
        let grad_w = kernels.spiky_gradient(r_ij, r2);
        let ratio = kernels.spiky(r2) * a.shifting.inverse_spacing_weight;
        let ratio2 = ratio * ratio;
        concentration_gradient += grad_w;
        shifting_gradient += grad_w * (R::ONE + R::from_f64(CLUMPING_WEIGHT) * ratio2 * ratio2);
        position_divergence -= r_ij.dot(grad_w);
    });
    let volume = a.fluid.mass / a.fluid.rest_density;
    let mut gradient = shifting_gradient * volume;
    let norm2 = concentration_gradient.dot(concentration_gradient);
    if position_divergence * volume < a.shifting.surface_divergence && norm2 > R::ZERO {
        let normal = concentration_gradient * (R::ONE / norm2.sqrt());
        gradient = gradient - normal * gradient.dot(normal);
    }
    let [x, y, z] = a.velocity.at(i);
    let speed = (x * x + y * y + z * z).sqrt();
    let diffusion = (a.shifting.coefficient * a.dt * speed).min(kernels.h2 * R::from_f64(LARGEST_DIFFUSION));
    let shift = gradient * -diffusion;
    let length2 = shift.dot(shift);
    let largest = a.shifting.largest_shift;
    if length2 > largest * largest {
        shift * (largest / length2.sqrt())
    } else {
        shift
    }
}

/// The shifting pass for particle `i`: its shift, zero for fixed boundary particles.
#[inline(always)]
pub fn shifting_pass<R: Real, N: Neighbors>(i: usize, a: &ShiftingArgs<R, N>) {
    let shift = if a.fluid.is_boundary(a.id.at(i)) { Vec3::zero() } else { particle_shift(i, a) };
    // SAFETY: invocation i owns entry i.
    unsafe { a.shift.write(i, [shift.x, shift.y, shift.z]) };
}

/// Arguments of the pass that moves particles by their shift.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ShiftArgs<'a, R, T = Open> {
    /// Moves particles that crossed a periodic face back into the domain.
    pub topology: T,
    pub shift: Vec3View<'a, R>,
    /// Position (m).
    pub position: Vec3ViewMut<'a, f64>,
}

/// x_i += shift_i, after leap-frog has moved every particle with the shifts computed over the
/// step's positions.
#[inline(always)]
pub fn shift_pass<R: Real, T: Topology>(i: usize, a: &ShiftArgs<R, T>) {
    let shift = a.shift.at(i);
    let mut x = a.position.at(i);
    for k in 0..3 {
        x[k] += shift[k].to_f64();
    }
    // SAFETY: invocation i owns entry i.
    unsafe { a.position.write(i, a.topology.wrap(x)) };
}
