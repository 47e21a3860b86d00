//! Why a step stopped: a run gone unstable, with its diagnosis, or a backend's fault.

use crate::scene::ViscousVelocity;
use std::fmt;

/// Why a run stopped early.
#[derive(Debug, Clone, PartialEq)]
pub struct Instability {
    pub step: u64,
    pub time_s: f64,
    /// Fluid particles with a non-finite velocity or density, or a speed above the runaway
    /// limit.
    pub bad_particles: usize,
    pub max_speed_m_s: f64,
    pub runaway_speed_m_s: f64,
    pub dt_s: f64,
    pub stability_bound_s: f64,
    /// The velocity the viscous terms read.
    pub viscous_velocity: ViscousVelocity,
    /// Whether pressure was solved (divergence-free) rather than Eq. (6)'s.
    pub pressure_solved: bool,
    /// The first non-finite value a frame would have held (field, particle id, value), where
    /// that is what stopped the run.
    pub non_finite: Option<String>,
    /// The implicit viscosity solve that missed its tolerance, where that is what stopped the
    /// run.
    pub unconverged_solve: Option<Box<UnconvergedSolve>>,
}

/// A solve that stopped above its tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnconvergedSolve {
    pub solve: Solve,
    pub iterations: u32,
    /// The last residual's norm over that of v* (implicit viscosity), or the fluid's mean
    /// error over rho0 (pressure).
    pub relative_residual: f64,
    pub tolerance: f64,
}

/// Which solve of a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Solve {
    ImplicitViscosity,
    /// The divergence-free pressure's divergence solve.
    Divergence,
    /// The divergence-free pressure's density solve.
    Density,
}

impl fmt::Display for Instability {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(solve) = &self.unconverged_solve {
            let (step, t, dt) = (self.step, self.time_s, self.dt_s);
            let (iterations, error, tolerance) = (solve.iterations, solve.relative_residual, solve.tolerance);
            return match solve.solve {
                Solve::ImplicitViscosity => write!(
                    f,
                    "the implicit viscosity solve did not converge at step {step} (t = {t:.6e} s, dt = {dt:.3e} s): after {iterations} iterations its residual was {error:.3e} of its first, above the tolerance {tolerance:.1e}. Raise material.viscosity.implicit.max_iterations, lower dt (simulation.time_step.safety_factor or fixed_s), or set material.viscosity.implicit.on_no_convergence = \"warn\" to go on and count such steps."
                ),
                Solve::Divergence | Solve::Density => {
                    let name = if solve.solve == Solve::Divergence { "divergence" } else { "density" };
                    write!(
                        f,
                        "the {name} solve did not converge at step {step} (t = {t:.6e} s, dt = {dt:.3e} s): after {iterations} sweeps the fluid's mean {name} error was {error:.3e} of rho0, above the tolerance {tolerance:.1e}. Raise simulation.divergence_free.max_iterations, lower simulation.divergence_free.cfl_factor or max_time_step_s, or set simulation.divergence_free.on_no_convergence = \"warn\" to go on and count such steps."
                    )
                }
            };
        }
        match &self.non_finite {
            Some(what) => write!(
                f,
                "the run went unstable at step {} (t = {:.6e} s): {} particle(s) with a non-finite value, the first {what}; nothing non-finite was written. ",
                self.step, self.time_s, self.bad_particles
            )?,
            None => write!(
                f,
                "the run went unstable at step {} (t = {:.6e} s): {} particle(s) with a non-finite velocity or density, or a speed above {:.3} m/s (largest finite speed {:.3e} m/s). ",
                self.step, self.time_s, self.bad_particles, self.runaway_speed_m_s, self.max_speed_m_s
            )?,
        }
        if self.dt_s > self.stability_bound_s {
            write!(
                f,
                "Likely cause: dt = {:.3e} s is above the Eq. (10) bound {:.3e} s; lower simulation.time_step.fixed_s or safety_factor (docs/tradeoff.md gives how far above the bound each viscosity operator was measured to stay stable).",
                self.dt_s, self.stability_bound_s
            )
        } else if self.pressure_solved {
            write!(
                f,
                "dt = {:.3e} s was within the bound of the terms not solved; likely causes: a CFL step too long for the flow (lower simulation.divergence_free.cfl_factor or max_time_step_s), pressure left unsolved between steps (raise simulation.divergence_free.min_iterations or lower its tolerances, or its relaxation), or particles injected into walls.",
                self.dt_s
            )
        } else {
            write!(
                f,
                "dt = {:.3e} s was within the Eq. (10) bound {:.3e} s; likely causes: free-surface tension from Eq. (6) at a high sound speed (set material.clamp_negative_pressure = true), a sound speed too low for the flow speed (walls give way above Mach 1), or particles injected into walls; or try a smaller simulation.time_step.safety_factor.",
                self.dt_s, self.stability_bound_s
            )
        }
    }
}

/// Why a step stopped.
#[derive(Debug)]
pub enum StepError<F> {
    Unstable(Instability),
    /// The backend failed.
    Backend(F),
}

impl<F: fmt::Display> fmt::Display for StepError<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StepError::Unstable(i) => i.fmt(f),
            StepError::Backend(e) => e.fmt(f),
        }
    }
}

impl<F> From<Instability> for StepError<F> {
    fn from(i: Instability) -> Self {
        StepError::Unstable(i)
    }
}

impl StepError<std::convert::Infallible> {
    /// The instability, on a backend that cannot fail otherwise.
    pub fn instability(self) -> Instability {
        match self {
            StepError::Unstable(i) => i,
            StepError::Backend(never) => match never {},
        }
    }
}
