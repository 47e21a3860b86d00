//! The state of a run that is the same on every backend: the fluid's constants, the physics
//! variant, the clock and time step, the inlets, the particle counts and the guard.

use super::{Diagnostics, Instability, Solve, UnconvergedSolve};
use crate::run::summary::Solves;
use crate::scene::inlet::Inlet;
use crate::scene::{DensityKernelKind, DivergenceFree, ImplicitViscosity, NoConvergence, ViscousVelocity};
use crate::simulation::model::{Model, SolveReport};
use crate::simulation::particles::Particles;
use crate::time_step::{Limit, TimeStepper};
use coil_kernels::fluid::Fluid;
use coil_kernels::nozzle::NozzleTube;
use coil_kernels::shifting_sun2017::Shifting;
use coil_kernels::Real;

pub struct RunState<R: Real, M: Model<R>> {
    pub fluid: Fluid<R>,
    pub model: M,
    pub(crate) inlets: Vec<Inlet>,
    pub stepper: TimeStepper,
    /// Simulated time (s).
    pub time: f64,
    pub steps: u64,
    pub(crate) previous_dt: Option<f64>,
    /// Fluid particles removed for leaving the domain box.
    pub removed: u64,
    /// Fluid particles injected by inlets.
    pub injected: u64,
    pub(crate) fluid_capacity: usize,
    /// When (s) an inlet first had a layer due that the fluid capacity could not take; from
    /// then on the jets run only as particles leave the domain.
    pub capacity_reached_at: Option<f64>,
    pub(crate) fluid_count: usize,
    pub(crate) next_id: u32,
    /// Figures of the fluid after the last readout; the velocity CFL reads its largest speed.
    pub diagnostics: Diagnostics,
    /// A speed no particle can reach physically (m/s): twice the free fall across the domain
    /// plus the fastest jet, plus 0.1 c.
    pub runaway_speed: f64,
    pub last_dt: f64,
    pub last_limit: Limit,
    /// The kernel of Eq. (5): which monomorphised density pass each step launches.
    pub density_kernel: DensityKernelKind,
    /// delta h c of the continuity equation's density diffusion (m^2/s), where density comes
    /// from it (the particles then hold a density rate).
    pub density_diffusivity: R,
    /// Which velocity the viscous terms read.
    pub viscous_velocity: ViscousVelocity,
    /// Particle shifting's constants, where the scene shifts particles (the particles then
    /// hold a shift).
    pub shifting: Option<Shifting<R>>,
    /// The implicit viscosity solve's settings, where viscosity is solved implicitly.
    pub implicit: Option<ImplicitViscosity>,
    /// The implicit solves of this run so far.
    pub solves: SolveStatistics,
    /// The pressure solves' settings, where pressure is solved for a divergence-free flow.
    pub pressure_solve: Option<DivergenceFree>,
    /// The divergence and density solves of this run so far.
    pub divergence_solves: SolveStatistics,
    pub density_solves: SolveStatistics,
}

/// Iterations of a run's solves of one kind.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveStatistics {
    pub steps: u64,
    pub iterations: u64,
    pub largest_iterations: u32,
    /// Steps whose solve stopped above its tolerance.
    pub unconverged: u64,
    pub last: Option<SolveReport>,
}

impl SolveStatistics {
    fn record(&mut self, report: SolveReport) {
        self.steps += 1;
        self.iterations += u64::from(report.iterations);
        self.largest_iterations = self.largest_iterations.max(report.iterations);
        self.last = Some(report);
        if !report.converged {
            self.unconverged += 1;
        }
    }

    /// What the summary says of these solves, run at `tolerance` and `max_iterations`.
    pub fn summary(&self, tolerance: f64, max_iterations: u32) -> Solves {
        Solves {
            mean_iterations: self.mean_iterations(),
            largest_iterations: self.largest_iterations,
            unconverged_steps: self.unconverged,
            tolerance,
            max_iterations,
        }
    }

    /// Mean iterations per step.
    pub fn mean_iterations(&self) -> f64 {
        if self.steps == 0 {
            0.0
        } else {
            self.iterations as f64 / self.steps as f64
        }
    }
}

impl<R: Real, M: Model<R>> RunState<R, M> {
    /// Fluid particles now in the run.
    pub fn fluid_count(&self) -> usize {
        self.fluid_count
    }

    pub fn boundary_count(&self) -> usize {
        self.fluid.boundary_count as usize
    }

    /// The run's inlets.
    pub fn inlets(&self) -> &[Inlet] {
        &self.inlets
    }

    /// Fluid particles the run has room for: the initial fluid plus all inlets may inject.
    pub fn fluid_capacity(&self) -> usize {
        self.fluid_capacity
    }

    /// Each inlet's nozzle tube now.
    pub fn inlet_tubes(&self) -> impl Iterator<Item = NozzleTube<R>> + '_ {
        self.inlets.iter().map(|inlet| inlet.tube(self.time))
    }

    /// dt for the next step and what limits it.
    pub fn next_dt(&self) -> (f64, Limit) {
        self.stepper.next(self.diagnostics.max_speed)
    }

    /// Algorithm 1, line 1: every inlet appends to `staging` the layers due after `dt` from
    /// now, within `room` particles in all and the fluid capacity. Returns how many it added.
    pub(crate) fn inject(&mut self, dt: f64, room: usize, staging: &mut Particles<R>) -> usize {
        let room = room.min(self.fluid_capacity - self.fluid_count);
        let mut added = 0;
        for inlet in &mut self.inlets {
            added += inlet.inject(self.time, dt, room - added, &mut self.next_id, staging);
        }
        self.count_injected(added);
        added
    }

    /// Counts the particles an injection added, and notes when the inlets first found the
    /// fluid capacity full.
    fn count_injected(&mut self, added: usize) {
        self.fluid_count += added;
        self.injected += added as u64;
        let room = self.fluid_capacity - self.fluid_count;
        if self.capacity_reached_at.is_none() && self.inlets.iter().any(|inlet| inlet.starved(room)) {
            self.capacity_reached_at = Some(self.time);
        }
    }

    /// Counts particles the sort dropped for leaving the domain.
    pub(crate) fn count_removed(&mut self, removed: usize) {
        self.removed += removed as u64;
        self.fluid_count -= removed;
    }

    /// Leap-frog's kick: half of this and the previous step (half of this one at the start).
    pub(crate) fn kick_dt(&self, dt: f64) -> f64 {
        match self.previous_dt {
            Some(prev) => 0.5 * (prev + dt),
            None => 0.5 * dt,
        }
    }

    /// The clock after a step of `dt` (s) limited by `limit`.
    pub(crate) fn advance_clock(&mut self, dt: f64, limit: Limit) {
        self.previous_dt = Some(dt);
        self.time += dt;
        self.steps += 1;
        self.last_dt = dt;
        self.last_limit = limit;
    }

    /// Sets the clock as a checkpoint left it: time (s), steps, and the last step's dt (s) and
    /// limit (`previous_dt` None before the first step).
    pub(crate) fn restore_clock(&mut self, time: f64, steps: u64, previous_dt: Option<f64>, last_dt: f64, last_limit: Limit) {
        self.time = time;
        self.steps = steps;
        self.previous_dt = previous_dt;
        self.last_dt = last_dt;
        self.last_limit = last_limit;
    }

    /// Sets the particle counts as a checkpoint left them.
    pub(crate) fn restore_counts(
        &mut self,
        fluid_count: usize,
        removed: u64,
        injected: u64,
        next_id: u32,
        capacity_reached_at: Option<f64>,
    ) {
        self.fluid_count = fluid_count;
        self.removed = removed;
        self.injected = injected;
        self.next_id = next_id;
        self.capacity_reached_at = capacity_reached_at;
    }

    /// Takes in a diagnostics readout: its figures, and the particles the sorts dropped since
    /// the last one that were not counted then.
    pub(crate) fn record(&mut self, readout: super::backend::Readout) {
        self.diagnostics = readout.figures;
        self.count_live(readout.live);
    }

    /// Counts as removed the fluid particles missing from the `live` particles (boundary
    /// included) that a backend reports.
    pub(crate) fn count_live(&mut self, live: usize) {
        let fluid_now = live - self.boundary_count();
        self.count_removed(self.fluid_count - fluid_now);
    }

    /// Counts a step's implicit solve; a solve that missed its tolerance stops the run unless
    /// the scene asks to go on.
    pub(crate) fn record_solve(&mut self, report: SolveReport) -> Result<(), Instability> {
        self.solves.record(report);
        match self.implicit {
            Some(settings) if !report.converged && settings.on_no_convergence == NoConvergence::Stop => {
                Err(self.unconverged(Solve::ImplicitViscosity, report, settings.tolerance))
            }
            _ => Ok(()),
        }
    }

    /// Counts a step's divergence and density solves; one that missed its tolerance stops the
    /// run where the scene asks.
    pub(crate) fn record_pressure_solves(&mut self, [divergence, density]: [SolveReport; 2]) -> Result<(), Instability> {
        self.divergence_solves.record(divergence);
        self.density_solves.record(density);
        let Some(settings) = self.pressure_solve else { return Ok(()) };
        if settings.on_no_convergence == NoConvergence::Stop {
            if !divergence.converged {
                return Err(self.unconverged(Solve::Divergence, divergence, settings.divergence_tolerance));
            }
            if !density.converged {
                return Err(self.unconverged(Solve::Density, density, settings.density_tolerance));
            }
        }
        Ok(())
    }

    fn unconverged(&self, solve: Solve, report: SolveReport, tolerance: f64) -> Instability {
        let mut diagnosis = self.instability(0, None);
        diagnosis.unconverged_solve = Some(Box::new(UnconvergedSolve {
            solve,
            iterations: report.iterations,
            relative_residual: report.relative_residual,
            tolerance,
        }));
        diagnosis
    }

    /// The guard: the latest diagnostics must show no runaway particle.
    pub(crate) fn check(&self) -> Result<(), Instability> {
        if self.diagnostics.bad_particles == 0 {
            return Ok(());
        }
        Err(self.instability(self.diagnostics.bad_particles as usize, None))
    }

    /// The run's state as the diagnosis of an instability of `bad_particles`, found by the
    /// guard or (`non_finite`: what was not finite) in a frame about to be written.
    pub(crate) fn instability(&self, bad_particles: usize, non_finite: Option<String>) -> Instability {
        Instability {
            step: self.steps,
            time_s: self.time,
            bad_particles,
            max_speed_m_s: self.diagnostics.max_speed,
            runaway_speed_m_s: self.runaway_speed,
            dt_s: self.last_dt,
            stability_bound_s: self.stepper.bound.dt().0,
            viscous_velocity: self.viscous_velocity,
            pressure_solved: self.pressure_solve.is_some(),
            non_finite,
            unconverged_solve: None,
        }
    }
}
