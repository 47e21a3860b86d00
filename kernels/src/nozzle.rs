//! The nozzle of a jet inlet (paper Sec. III-C) as a short tube that pushes the fluid inside it.
//!
//! Injected layers are born inside the tube, upstream of its exit, and move at the jet velocity
//! until they leave it. Without the tube a fresh layer is free the moment it appears: when the
//! rope below slows down (it must, to buckle on the plate), the next layers are placed on top of
//! it at the inlet's clock, the rope's top is crushed instead of the rope being pushed, and the
//! column bulges under the nozzle. A real nozzle is a pipe that imposes the exit velocity, and
//! the tube's particles also give the first free layers a full kernel support from above.

use crate::fluid::Fluid;
use crate::real::Real;
use crate::view::{Vec3View, Vec3ViewMut, View};

/// One nozzle's tube at this step, in SI units.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NozzleTube<R> {
    /// Centre of the exit plane (m).
    pub exit: [f64; 3],
    /// Unit vector along the jet.
    pub axis: [f64; 3],
    /// Unit vectors spanning the exit plane; a rectangle's width runs along the first.
    pub across: [[f64; 3]; 2],
    /// Half-extents (m) of the bore along `across`: a rectangle's half width and half depth, or
    /// the radius (first entry) of a circle. Each includes half a particle spacing of clearance
    /// plus the inlet's wobble.
    pub half_extent: [f64; 2],
    /// 1 for a round bore, 0 for a rectangular one.
    pub round: u32,
    /// Length of the tube upstream of the exit (m), with half a spacing of clearance beyond
    /// where layers are born.
    pub length: f64,
    /// Velocity of the fluid in the tube (m/s): the jet speed along the axis plus the nozzle's
    /// own motion.
    pub velocity: [R; 3],
}

impl<R: Real> NozzleTube<R> {
    /// Whether particle `i` is fluid inside the bore, whose motion the tube sets.
    #[inline(always)]
    fn moves(&self, i: usize, fluid: &Fluid<R>, id: &View<u32>, position: &Vec3View<f64>) -> bool {
        !fluid.is_boundary(id.at(i)) && self.contains(position.at(i))
    }

    /// Whether a point at `x` (m) lies inside the bore, between the tube's inlet and its exit.
    #[inline(always)]
    pub fn contains(&self, x: [f64; 3]) -> bool {
        let d = [x[0] - self.exit[0], x[1] - self.exit[1], x[2] - self.exit[2]];
        let along = d[0] * self.axis[0] + d[1] * self.axis[1] + d[2] * self.axis[2];
        if !(along < 0.0 && along >= -self.length) {
            return false;
        }
        let a = d[0] * self.across[0][0] + d[1] * self.across[0][1] + d[2] * self.across[0][2];
        let b = d[0] * self.across[1][0] + d[1] * self.across[1][1] + d[2] * self.across[1][2];
        let (ea, eb) = (self.half_extent[0], self.half_extent[1]);
        if self.round != 0 {
            a * a + b * b <= ea * ea
        } else {
            a.abs() <= ea && b.abs() <= eb
        }
    }
}

/// Arguments of the nozzle pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NozzleArgs<'a, R> {
    pub fluid: Fluid<R>,
    pub tube: NozzleTube<R>,
    pub id: View<'a, u32>,
    pub position: Vec3View<'a, f64>,
    /// Zeroed inside the tube (m/s^2).
    pub acceleration: Vec3ViewMut<'a, R>,
    /// Set to the tube's velocity inside it (m/s), so leap-frog moves the particle with the
    /// nozzle flow.
    pub velocity_half: Vec3ViewMut<'a, R>,
}

/// Runs between the accelerations and leap-frog: fluid particle `i` inside the tube moves at
/// the tube's velocity, whatever the forces on it.
#[inline(always)]
pub fn nozzle_pass<R: Real>(i: usize, a: &NozzleArgs<R>) {
    if !a.tube.moves(i, &a.fluid, &a.id, &a.position) {
        return;
    }
    // SAFETY: invocation i owns entry i.
    unsafe {
        a.acceleration.write(i, [R::ZERO; 3]);
        a.velocity_half.write(i, a.tube.velocity);
    }
}

/// Arguments of the pass that keeps the tube's fluid unshifted.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NozzleShiftArgs<'a, R> {
    pub fluid: Fluid<R>,
    pub tube: NozzleTube<R>,
    pub id: View<'a, u32>,
    pub position: Vec3View<'a, f64>,
    /// Zeroed inside the tube (m).
    pub shift: Vec3ViewMut<'a, R>,
}

/// Runs between particle shifting and leap-frog: fluid particle `i` inside the tube keeps the
/// inlet's lattice, on which the next layers are laid, so it is not shifted.
#[inline(always)]
pub fn nozzle_shift_pass<R: Real>(i: usize, a: &NozzleShiftArgs<R>) {
    if !a.tube.moves(i, &a.fluid, &a.id, &a.position) {
        return;
    }
    // SAFETY: invocation i owns entry i.
    unsafe { a.shift.write(i, [R::ZERO; 3]) };
}
