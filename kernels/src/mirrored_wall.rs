//! Mirrored walls: each wall particle shows the fluid the flow mirrored through the wall surface,
//! the fixed ghost particles of Marrone et al. 2011 (Comput. Methods Appl. Mech. Engrg. 200)
//! for a wall at rest. Its velocity is minus the fluid's at its mirror image (no slip on the
//! surface) and its pressure the fluid's there plus the hydrostatic difference (Adami, Hu &
//! Adams 2012, J. Comput. Phys. 231, Eq. (27), with the wall's acceleration zero).
//!
//! The paper's walls (Sec. III-B) are at rest with their density summed by Eq. (5). Their zero
//! velocity sits half a spacing and more behind the wall surface, so the no-slip plane moves
//! half a spacing into the wall and a channel flows as if it were one spacing wider; and their
//! lattice density ignores how much the fluid above them is compressed, so the layer of fluid on
//! a floor must compress further to carry the column. Each wall layer must mirror the fluid
//! layer it faces: the paper's viscous operator, Eq. (8) then (9), couples particles two layers
//! apart, so a deeper layer left at rest, or given the mean velocity of the fluid around itself
//! (Adami's velocity rule), drives alternate fluid layers apart.

use crate::cell_grid::Neighborhood;
use crate::density::pressure;
use crate::fluid::Fluid;
use crate::real::Real;
use crate::topology::{Open, Topology};
use crate::vec3::{Mat3, SymTensor, Vec3};
use crate::view::{Vec3View, Vec3ViewMut, View, ViewMut};

/// The fluid's velocity (m/s) and pressure (Pa) at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FluidSample<R> {
    pub velocity: Vec3<R>,
    pub pressure: R,
}

/// The largest leverage w0 m^T C^-1 m of the sample point for which the velocity fit is used:
/// m is the mean offset of the neighbors from the point and C their weighted covariance, so
/// this is the squared distance of the extrapolation in units of the neighbors' spread, and
/// the fit's noise there grows as its square root. Mirror images inside the fluid, and the
/// fluid next to a wall, have at most 4 (one-sided to the wall surface itself, up to 22); a
/// single layer of fluid on a plate, rough by 0.1 spacing or less, has 46 and more at the
/// mirror image a spacing above it. There a fit turns the velocity differences within the
/// layer into a wall-normal slope and extrapolates it, up to 50 times the velocity noise of
/// the layer; Eq. (8) then (9) reach those wall particles, two layers down, and the wall's
/// velocities threw particles of Huppert's thinning current through the plate.
pub const MAX_LEVERAGE: f64 = 25.0;

/// The fluid at a point `x` (m) from the fluid particles within h of it. Velocity: a linear fit
/// weighted by poly6 (moving least squares), exact for linear fields, so one-sided neighbors
/// next to a wall do not bias it; the kernel-weighted mean (Shepard) where the neighbors are
/// too flat, or the point too far from them, for a fit ([`MAX_LEVERAGE`]). Pressure: the
/// kernel-weighted mean, which stays within the fluid's values where a fit could overshoot
/// them, so a wall never answers a pressure wave with more than it brought (the tank measured
/// the same with either). Rest at zero pressure where there is no fluid.
#[inline(always)]
pub fn fluid_at<R: Real, T: Topology>(
    x: [f64; 3],
    neighborhood: &Neighborhood<T>,
    id: &View<u32>,
    velocity: &Vec3ViewMut<R>,
    density: &ViewMut<R>,
    fluid: &Fluid<R>,
) -> FluidSample<R> {
    let inverse_h = R::ONE / fluid.kernels.h;
    // Moments of the weights over offsets q = (x_j - x) / h, and of velocity; sum of pressure.
    let mut w0 = R::ZERO;
    let mut w1 = Vec3::zero();
    let mut w2 = SymTensor::zero();
    let mut v0 = Vec3::zero();
    let mut v1 = Mat3::zero();
    let mut p0 = R::ZERO;
    neighborhood.for_each_particle_near(x, fluid.kernels.h2, |j, r, r2: R| {
        if !fluid.is_boundary(id.at(j)) {
            let w = fluid.kernels.poly6(r2);
            let q = r * (-inverse_h);
            let [vx, vy, vz] = velocity.at(j);
            let v = Vec3::new(vx, vy, vz);
            let p = pressure(density.at(j), fluid);
            w0 += w;
            w1 += q * w;
            w2 = w2 + SymTensor::outer(q).scaled(w);
            v0 += v * w;
            v1.add_outer(q * w, v);
            p0 += p * w;
        }
    });
    if !(w0 > R::ZERO) {
        return FluidSample { velocity: Vec3::zero(), pressure: R::ZERO };
    }
    // The fit v(q) = mean_v + B^T (q - mean_q), centred so that its slope B solves the weighted
    // covariance C B = sum w (q - mean_q) v^T; at q = 0 it is mean_v - B^T mean_q, which needs
    // only u = C^-1 mean_q, and sum w (q - mean_q) v^T = V1 - mean_q V0^T.
    let inv_w0 = R::ONE / w0;
    let mean_q = w1 * inv_w0;
    let mean_v = v0 * inv_w0;
    let covariance = w2 + SymTensor::outer(mean_q).scaled(-w0);
    // Offsets spread less than 0.03 h about their mean (one neighbor, at a free surface's edge)
    // leave a covariance of rounding noise, whose inverse is arbitrary; the mean is all they
    // determine.
    let spread = covariance.trace() > R::from_f64(1e-3) * w0;
    let fit = covariance.solve(mean_q).filter(|u| spread && w0 * mean_q.dot(*u) <= R::from_f64(MAX_LEVERAGE));
    let velocity = match fit {
        Some(u) => {
            let mut centred = v1;
            centred.add_outer(mean_q, -v0);
            mean_v - centred.transpose_dot(u)
        }
        None => mean_v,
    };
    FluidSample { velocity, pressure: p0 * inv_w0 }
}

/// Arguments of the mirrored-wall pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct MirroredWallArgs<'a, R, T = Open> {
    pub neighborhood: Neighborhood<'a, T>,
    pub fluid: Fluid<R>,
    pub id: View<'a, u32>,
    /// Each wall particle's mirror image through the wall surface it belongs to (m), indexed by
    /// id (wall particles never move, so this needs no reordering).
    pub mirror: Vec3View<'a, f64>,
    /// Velocity the viscous terms read (m/s; see `leapfrog`): fluid entries are read, wall
    /// entries written.
    pub velocity: Vec3ViewMut<'a, R>,
    /// Density (kg/m^3) after the density pass: fluid entries are read; wall entries are
    /// written as the density whose Eq. (6) pressure is the wall's.
    pub density: ViewMut<'a, R>,
}

/// The mirrored-wall pass for particle `i`; fluid particles are left alone. Runs after the
/// density pass and before the viscous and pressure terms read velocity and density.
#[inline(always)]
pub fn mirrored_wall_pass<R: Real, T: Topology>(i: usize, a: &MirroredWallArgs<R, T>) {
    let id = a.id.at(i);
    if !a.fluid.is_boundary(id) {
        return;
    }
    let mirror = a.mirror.at(id as usize);
    let x = a.neighborhood.position.at(i);
    let f = fluid_at(mirror, &a.neighborhood, &a.id, &a.velocity, &a.density, &a.fluid);
    // Hydrostatics from the mirror image down to the wall particle: p += rho0 g · (x - mirror).
    let below = Vec3::from_f64([x[0] - mirror[0], x[1] - mirror[1], x[2] - mirror[2]]);
    let p = f.pressure + a.fluid.rest_density * a.fluid.gravity.dot(below);
    let v = -f.velocity;
    // SAFETY: invocation i owns entry i, a wall entry; the entries it reads are fluid ones,
    // which no invocation of this pass writes.
    unsafe {
        a.velocity.write(i, [v.x, v.y, v.z]);
        // Where pressure is solved (c = 0) there is no Eq. (6) to invert: the wall keeps its
        // summed density and pushes as the paper's wall does (`dfsph_bender2017`); only its
        // velocity mirrors the fluid, which is what makes it no-slip.
        if a.fluid.sound_speed2 > R::ZERO {
            a.density.write(i, a.fluid.rest_density + p / a.fluid.sound_speed2);
        }
    }
}
