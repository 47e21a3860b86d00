//! Rheology: kinematic viscosity nu (m^2/s) as a function of the shear rate D (1/s).

use crate::real::Real;

/// A viscosity law nu(D). The law is a type parameter of the stress kernel, so a Newtonian run
/// never evaluates the Cross model (not even a branch per particle).
pub trait Rheology<R: Real>: Copy + Send + Sync {
    /// The law's name in PTX kernel names (`stress_<NAME>_f32`).
    const NAME: &'static str;
    /// Kinematic viscosity (m^2/s) at shear rate `shear_rate` (1/s).
    fn viscosity(&self, shear_rate: R) -> R;
    /// The largest viscosity the law reaches (m^2/s), which bounds dt by Eq. (10).
    fn max_viscosity(&self) -> R;
}

/// Constant viscosity: the Cross model with K = 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Newtonian<R> {
    /// nu0 (m^2/s).
    pub nu0: R,
}

impl<R: Real> Rheology<R> for Newtonian<R> {
    const NAME: &'static str = "newtonian";
    #[inline(always)]
    fn viscosity(&self, _shear_rate: R) -> R {
        self.nu0
    }
    #[inline(always)]
    fn max_viscosity(&self) -> R {
        self.nu0
    }
}

/// The Cross model, Eq. (3): nu(D) = nu_inf + (nu0 - nu_inf) / (1 + (K D)^n).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cross<R> {
    /// Zero-shear viscosity nu0 (m^2/s).
    pub nu0: R,
    /// Infinite-shear viscosity nu_inf (m^2/s).
    pub nu_inf: R,
    /// Consistency K (s).
    pub k: R,
    /// Rate index n (dimensionless).
    pub n: R,
}

impl<R: Real> Rheology<R> for Cross<R> {
    const NAME: &'static str = "cross";
    #[inline(always)]
    fn viscosity(&self, shear_rate: R) -> R {
        let kd = self.k * shear_rate;
        // n = 1 (every scene of the paper but Fig. 4) skips exp2/log2; the branch is uniform
        // across all threads of a launch.
        let kd_n = if self.n == R::ONE { kd } else { kd.powf(self.n) };
        self.nu_inf + (self.nu0 - self.nu_inf) / (R::ONE + kd_n)
    }
    /// nu0: validation keeps nu_inf <= nu0, so the viscosity is largest at zero shear.
    #[inline(always)]
    fn max_viscosity(&self) -> R {
        self.nu0
    }
}
