//! Leap-frog time integration (Algorithm 1, line 18).

use crate::fluid::Fluid;
use crate::real::Real;
use crate::topology::{Open, Topology};
use crate::view::{Vec3View, Vec3ViewMut, View};

/// Arguments of the integration pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct LeapfrogArgs<'a, R, T = Open> {
    pub fluid: Fluid<R>,
    /// Moves particles that crossed a periodic face back into the domain.
    pub topology: T,
    /// This step's dt (s).
    pub dt: R,
    /// Interval over which the half-step velocity is kicked (s): (dt_prev + dt) / 2, or dt / 2
    /// on the first step, when the half-step velocity still equals the initial velocity.
    pub kick_dt: R,
    pub id: View<'a, u32>,
    pub acceleration: Vec3View<'a, R>,
    /// Position (m). Integrated in f64 in both precisions: a particle at 1 mm/s with
    /// dt = 1e-6 s moves 1 nm a step, below half an f32 ulp anywhere beyond 0.017 m from the
    /// origin, so f32 positions would round such motion away.
    pub position: Vec3ViewMut<'a, f64>,
    /// v at the half step, v_{n-1/2} in, v_{n+1/2} out (m/s).
    pub velocity_half: Vec3ViewMut<'a, R>,
    /// v at the full step n+1 as v_{n+1/2} + a_n dt / 2 (m/s), which the frames, the guard and,
    /// by default, the viscous terms of the next step read.
    pub velocity: Vec3ViewMut<'a, R>,
}

/// Leap-frog for particle `i`: v_{n+1/2} = v_{n-1/2} + a_n dt, x_{n+1} = x_n + v_{n+1/2} dt.
/// Fixed boundary particles do not move.
///
/// The viscous terms of the next step read the full step (second order in time) or, as the
/// scene chooses, v_{n+1/2}. On a mode that viscosity damps at the rate lambda, a = -lambda v,
/// the full step makes the scheme v_{n+1} = (1 - 3 z / 2) v_n + z / 2 v_{n-1}, z = lambda dt,
/// stable only for z < 1, and the half step v_{n+1/2} = (1 - z) v_{n-1/2}, stable for z < 2.
/// The stiffest such mode is two particles closing in a thinned jet, where the clamped pressure
/// holds nothing apart: at 12 particles across the jet's diameter it grew 1.5 times a step at
/// the Eq. (10) bound with the full step (docs/tradeoff.md).
#[inline(always)]
pub fn leapfrog_pass<R: Real, T: Topology>(i: usize, a: &LeapfrogArgs<R, T>) {
    if a.fluid.is_boundary(a.id.at(i)) {
        return;
    }
    let acc = a.acceleration.at(i);
    let mut v_half = a.velocity_half.at(i);
    let mut x = a.position.at(i);
    let mut v = [R::ZERO; 3];
    let half_dt = a.dt * R::from_f64(0.5);
    let dt = a.dt.to_f64();
    for k in 0..3 {
        v_half[k] += acc[k] * a.kick_dt;
        x[k] += v_half[k].to_f64() * dt;
        v[k] = v_half[k] + acc[k] * half_dt;
    }
    // SAFETY: invocation i owns entry i.
    unsafe {
        a.velocity_half.write(i, v_half);
        a.position.write(i, a.topology.wrap(x));
        a.velocity.write(i, v);
    }
}
