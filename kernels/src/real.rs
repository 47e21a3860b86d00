//! Floating-point precision of the physics, chosen once per run (f32 or f64).
//!
//! Math that `core` lacks (`sqrt`, `exp2`, `log2`) goes to `std` on the host and to LLVM/NVVM
//! intrinsics on nvptx (f64 `exp2` and `log2`, which PTX lacks, to [`crate::f64_math`]): `libm`
//! would compile to slow table-driven software math on the device.

use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A floating-point type the kernels are generic over.
pub trait Real:
    Copy
    + Default
    + PartialOrd
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + core::fmt::Debug
{
    const ZERO: Self;
    const ONE: Self;
    const NAME: &'static str;

    fn from_f64(v: f64) -> Self;
    fn to_f64(self) -> f64;
    fn sqrt(self) -> Self;
    fn exp2(self) -> Self;
    fn log2(self) -> Self;
    fn abs(self) -> Self;
    fn is_finite(self) -> bool;

    /// Notes that a neighbor loop examines `n` candidates, each filtered by its distance in
    /// f64 (8 operations). Nothing for `f32` and `f64`; the host's operation counter counts them.
    #[inline(always)]
    fn tally_candidates(_n: usize) {}

    #[inline(always)]
    fn max(self, other: Self) -> Self {
        if self > other {
            self
        } else {
            other
        }
    }

    #[inline(always)]
    fn min(self, other: Self) -> Self {
        if self < other {
            self
        } else {
            other
        }
    }

    /// `self^e` for `self >= 0`; `0^e = 0` for the positive exponents of the Cross model.
    #[inline(always)]
    fn powf(self, e: Self) -> Self {
        if self > Self::ZERO {
            (e * self.log2()).exp2()
        } else {
            Self::ZERO
        }
    }
}

#[cfg(target_arch = "nvptx64")]
mod device_math {
    extern "C" {
        #[link_name = "llvm.sqrt.f32"]
        pub fn sqrt_f32(x: f32) -> f32;
        #[link_name = "llvm.sqrt.f64"]
        pub fn sqrt_f64(x: f64) -> f64;
        #[link_name = "llvm.nvvm.ex2.approx.f"]
        pub fn ex2_f32(x: f32) -> f32;
        #[link_name = "llvm.nvvm.lg2.approx.f"]
        pub fn lg2_f32(x: f32) -> f32;
    }
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const NAME: &'static str = "f32";

    #[inline(always)]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    #[cfg(not(target_arch = "nvptx64"))]
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[cfg(not(target_arch = "nvptx64"))]
    #[inline(always)]
    fn exp2(self) -> Self {
        f32::exp2(self)
    }
    #[cfg(not(target_arch = "nvptx64"))]
    #[inline(always)]
    fn log2(self) -> Self {
        f32::log2(self)
    }
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn sqrt(self) -> Self {
        unsafe { device_math::sqrt_f32(self) }
    }
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn exp2(self) -> Self {
        unsafe { device_math::ex2_f32(self) }
    }
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn log2(self) -> Self {
        unsafe { device_math::lg2_f32(self) }
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const NAME: &'static str = "f64";

    #[inline(always)]
    fn from_f64(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
    #[cfg(not(target_arch = "nvptx64"))]
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[cfg(not(target_arch = "nvptx64"))]
    #[inline(always)]
    fn exp2(self) -> Self {
        f64::exp2(self)
    }
    #[cfg(not(target_arch = "nvptx64"))]
    #[inline(always)]
    fn log2(self) -> Self {
        f64::log2(self)
    }
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn sqrt(self) -> Self {
        unsafe { device_math::sqrt_f64(self) }
    }
    // PTX has no f64 `ex2`/`lg2`: arithmetic in f64 instead of the f32 approximations, so that
    // an f64 run's Cross exponent is f64 on the device too.
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn exp2(self) -> Self {
        crate::f64_math::exp2(self)
    }
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn log2(self) -> Self {
        crate::f64_math::log2(self)
    }
}
