//! The smoothing kernels of Müller, Charypar & Gross 2003 (the paper's \[23\]), support radius `h`.

use crate::real::Real;
use crate::vec3::Vec3;

/// Kernel constants for one support radius, precomputed on the host.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct SmoothingKernels<R> {
    /// Support radius h (m).
    pub h: R,
    /// h^2 (m^2).
    pub h2: R,
    pub(crate) poly6_coefficient: R,
    pub(crate) spiky_coefficient: R,
    pub(crate) spiky_gradient_coefficient: R,
    pub(crate) viscosity_laplacian_coefficient: R,
    pub(crate) morris_laplacian_coefficient: R,
}

impl<R: Real> SmoothingKernels<R> {
    pub fn new(h: f64) -> Self {
        let pi = core::f64::consts::PI;
        let h3 = h * h * h;
        let h6 = h3 * h3;
        Self {
            h: R::from_f64(h),
            h2: R::from_f64(h * h),
            poly6_coefficient: R::from_f64(315.0 / (64.0 * pi * h6 * h3)),
            spiky_coefficient: R::from_f64(15.0 / (pi * h6)),
            spiky_gradient_coefficient: R::from_f64(-45.0 / (pi * h6)),
            viscosity_laplacian_coefficient: R::from_f64(45.0 / (pi * h6)),
            morris_laplacian_coefficient: R::from_f64(90.0 / (pi * h6)),
        }
    }

    /// The same kernels with the spiky gradient, the viscosity Laplacian and Morris's
    /// Laplacian multiplied by `gradient`, `laplacian` and `morris` (dimensionless): see the
    /// host's `calibrated_kernels`.
    pub fn corrected(self, gradient: f64, laplacian: f64, morris: f64) -> Self {
        Self {
            spiky_gradient_coefficient: self.spiky_gradient_coefficient * R::from_f64(gradient),
            viscosity_laplacian_coefficient: self.viscosity_laplacian_coefficient * R::from_f64(laplacian),
            morris_laplacian_coefficient: self.morris_laplacian_coefficient * R::from_f64(morris),
            ..self
        }
    }

    /// The spiky gradient's coefficient, -45 / (pi h^6) times any correction (1/m^6).
    #[inline(always)]
    pub fn spiky_gradient_coefficient(&self) -> R {
        self.spiky_gradient_coefficient
    }

    /// poly6: W(r) = 315 / (64 pi h^9) (h^2 - r^2)^3 for r < h (1/m^3). Used by Eq. (5).
    #[inline(always)]
    pub fn poly6(&self, r2: R) -> R {
        if r2 < self.h2 {
            let d = self.h2 - r2;
            self.poly6_coefficient * d * d * d
        } else {
            R::ZERO
        }
    }

    /// spiky: W(r) = 15 / (pi h^6) (h - r)^3 for r < h (1/m^3). Eq. (5) with it instead of
    /// poly6 makes the density the potential whose gradient Eq. (7) takes.
    #[inline(always)]
    pub fn spiky(&self, r2: R) -> R {
        if r2 < self.h2 {
            let d = self.h - r2.sqrt();
            self.spiky_coefficient * d * d * d
        } else {
            R::ZERO
        }
    }

    /// Gradient of spiky W(r) = 15 / (pi h^6) (h - r)^3 with respect to x_i, for
    /// `r_ij = x_i - x_j` (1/m^4). Used by Eq. (7), (8) and (9). Zero at r = 0, where its
    /// direction is undefined: coincident particles get finite (zero) pair forces.
    #[inline(always)]
    pub fn spiky_gradient(&self, r_ij: Vec3<R>, r2: R) -> Vec3<R> {
        if r2 < self.h2 && r2 > R::ZERO {
            let r = r2.sqrt();
            let d = self.h - r;
            r_ij * (self.spiky_gradient_coefficient * d * d / r)
        } else {
            Vec3::zero()
        }
    }

    /// Laplacian of Müller's viscosity kernel, 45 / (pi h^6) (h - r) for r < h (1/m^5).
    #[inline(always)]
    pub fn viscosity_laplacian(&self, r2: R) -> R {
        if r2 < self.h2 {
            self.viscosity_laplacian_coefficient * (self.h - r2.sqrt())
        } else {
            R::ZERO
        }
    }

    /// Morris, Fox & Zhu 1997's Laplacian weight F(r) = -2 (r_ij · grad_i W) / (r^2 + eta^2)
    /// with the spiky gradient and eta = 0.1 h (1/m^5): lap f_i = sum_j V_j (f_j - f_i) F(r).
    /// Built on a first derivative, it varies less than the viscosity kernel's Laplacian as
    /// neighbor layers slide past each other (1.6 % against 6 % at h = 2 s, over a shift of
    /// half a spacing); eta keeps coincident particles finite.
    #[inline(always)]
    pub fn morris_laplacian(&self, r2: R) -> R {
        if r2 < self.h2 {
            let r = r2.sqrt();
            let d = self.h - r;
            self.morris_laplacian_coefficient * d * d * r / (r2 + R::from_f64(0.01) * self.h2)
        } else {
            R::ZERO
        }
    }
}
