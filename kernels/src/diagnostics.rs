//! Figures of the fluid's state that guard a run (largest speed, compression, runaway
//! particles), combined over contiguous ranges of particles. The CPU backend reduces the ranges
//! with rayon every step; the CUDA backend writes one figure per range on the device and the
//! host combines them when it checks the run.

use crate::fluid::Fluid;
use crate::real::Real;
use crate::view::{Vec3View, View, ViewMut};

/// Figures over a set of fluid particles; boundary particles contribute nothing.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StateFigures {
    /// Largest finite speed (m/s).
    pub max_speed: f64,
    /// Largest compression (rho - rho0) / rho0, 0 where none is compressed: the weak
    /// compressibility that the sound speed bounds. A density deficit (a free surface's kernel
    /// sum cut off, or a particle flying alone) is not compression and is not counted.
    pub max_compression: f64,
    /// Fluid particles with a non-finite velocity or density, or a speed above the runaway
    /// limit.
    pub bad_particles: u64,
}

impl StateFigures {
    /// The figures of the union of two sets.
    #[inline(always)]
    pub fn combine(self, other: Self) -> Self {
        Self {
            max_speed: if other.max_speed > self.max_speed { other.max_speed } else { self.max_speed },
            max_compression: if other.max_compression > self.max_compression {
                other.max_compression
            } else {
                self.max_compression
            },
            bad_particles: self.bad_particles + other.bad_particles,
        }
    }
}

/// Arguments of the diagnostics pass.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct DiagnosticsArgs<'a, R> {
    pub fluid: Fluid<R>,
    /// Squared speed above which a particle counts as runaway (m^2/s^2).
    pub runaway_speed2: f64,
    pub id: View<'a, u32>,
    pub velocity: Vec3View<'a, R>,
    pub density: View<'a, R>,
}

/// The figures of particle `i` alone.
#[inline(always)]
pub fn particle_figures<R: Real>(i: usize, a: &DiagnosticsArgs<R>) -> StateFigures {
    if a.fluid.is_boundary(a.id.at(i)) {
        return StateFigures::default();
    }
    let [x, y, z] = a.velocity.at(i);
    let (x, y, z) = (x.to_f64(), y.to_f64(), z.to_f64());
    let speed2 = x * x + y * y + z * z;
    let rho0 = a.fluid.rest_density.to_f64();
    let density = a.density.at(i).to_f64();
    let (finite, finite_density) = (speed2.is_finite(), density.is_finite());
    let excess = if finite_density { density - rho0 } else { 0.0 };
    StateFigures {
        max_speed: if finite { Real::sqrt(speed2) } else { 0.0 },
        max_compression: if excess > 0.0 { excess / rho0 } else { 0.0 },
        bad_particles: u64::from(!finite || !finite_density || speed2 > a.runaway_speed2),
    }
}

/// Figures of particles `[range * range_len, (range + 1) * range_len)`, clipped to `count`.
#[inline(always)]
pub fn range_figures<R: Real>(range: usize, range_len: usize, count: usize, a: &DiagnosticsArgs<R>) -> StateFigures {
    let start = range * range_len;
    let end = if start + range_len < count { start + range_len } else { count };
    let mut figures = StateFigures::default();
    for i in start..end {
        figures = figures.combine(particle_figures(i, a));
    }
    figures
}

/// The diagnostics pass for range `range`: its figures into `out[range]`.
#[inline(always)]
pub fn diagnostics_pass<R: Real>(
    range: usize,
    range_len: usize,
    count: usize,
    a: &DiagnosticsArgs<R>,
    out: ViewMut<StateFigures>,
) {
    // SAFETY: invocation `range` owns entry `range`.
    unsafe { out.write(range, range_figures(range, range_len, count, a)) };
}
