//! Whether the domain wraps around: open (particles that leave it are dropped) or periodic along
//! some axes (they re-enter on the far side, and neighbors are found across the seam).
//!
//! A run's topology is a type: an open run's neighbor loop and leap-frog contain no periodic
//! code at all, and a periodic run's pay for the wrap only on the axes that wrap.

use core::fmt::Debug;

/// The shape of the domain, fixed for a run.
pub trait Topology: Copy + Debug + Send + Sync + 'static {
    /// Suffix of the PTX entries built for this topology ("" for open).
    const NAME: &'static str;
    /// Whether any axis wraps; the neighbor loop takes its periodic path only then.
    const PERIODIC: bool;
    /// Periods (m) of the axes that wrap, 0 for those that do not.
    fn periods(&self) -> [f64; 3];
    /// A position moved back into the domain across the faces that wrap (m).
    fn wrap(&self, x: [f64; 3]) -> [f64; 3];
}

/// Walls or nothing at the domain's faces: particles that leave are dropped.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Open;

impl Topology for Open {
    const NAME: &'static str = "";
    const PERIODIC: bool = false;
    #[inline(always)]
    fn periods(&self) -> [f64; 3] {
        [0.0; 3]
    }
    #[inline(always)]
    fn wrap(&self, x: [f64; 3]) -> [f64; 3] {
        x
    }
}

/// Periodic along the axes with a non-zero period: the domain box `origin .. origin + period`
/// tiles space along them.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Periodic {
    /// Lower corner of the domain box (m).
    pub origin: [f64; 3],
    /// Domain length along each axis that wraps, 0 along the others (m).
    pub period: [f64; 3],
}

impl Topology for Periodic {
    const NAME: &'static str = "periodic";
    const PERIODIC: bool = true;
    #[inline(always)]
    fn periods(&self) -> [f64; 3] {
        self.period
    }
    #[inline(always)]
    fn wrap(&self, mut x: [f64; 3]) -> [f64; 3] {
        for a in 0..3 {
            let l = self.period[a];
            if l > 0.0 {
                // A particle crosses at most one period per step (dt keeps moves below h).
                if x[a] < self.origin[a] {
                    x[a] += l;
                } else if x[a] >= self.origin[a] + l {
                    x[a] -= l;
                }
                // Rounding can land exactly on the upper face, which is the next period's cell.
                if x[a] >= self.origin[a] + l {
                    x[a] = self.origin[a];
                }
            }
        }
        x
    }
}

impl Periodic {
    /// The cell coordinate `c + offset` along axis `a` of a grid `cells` cells long there,
    /// `offset` within one period, wrapped when the axis wraps; `None` where an open axis ends.
    #[inline(always)]
    pub fn neighbor_cell(&self, a: usize, cells: u32, c: u32, offset: i32) -> Option<u32> {
        let d = cells as i32;
        let k = c as i32 + offset;
        if self.period[a] > 0.0 {
            // A remainder would leave a division-by-zero trap in the device code.
            Some(if k < 0 {
                k + d
            } else if k >= d {
                k - d
            } else {
                k
            } as u32)
        } else if k < 0 || k >= d {
            None
        } else {
            Some(k as u32)
        }
    }
}

/// How far below the support radius (relative) a periodic axis's cells may fall: a period
/// written in decimal, 0.0003 m for 3 h = 3 x 1e-4 m, is 3 h less a rounding. Pairs that the
/// grid then misses lie beyond h (1 - 1e-9), where every kernel is below 1e-9 of its peak.
pub const PERIODIC_ROUNDING: f64 = 1e-9;

/// The minimum-image difference along an axis of period `l` (m): the nearest copy of the
/// neighbor. Neighbors lie within h and periods are at least 3 h, so one shift suffices.
#[inline(always)]
pub fn minimum_image(d: f64, l: f64) -> f64 {
    if l > 0.0 {
        if d > 0.5 * l {
            return d - l;
        }
        if d < -0.5 * l {
            return d + l;
        }
    }
    d
}
