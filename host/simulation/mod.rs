//! One run: the backend-neutral run state and a backend's particles, advanced step by step
//! through Algorithm 1 by one schedule that every backend runs.

pub mod backend;
pub mod dfsph_bender2017;
pub mod host_particles;
pub mod implicit_weiler2018;
pub mod inlet;
pub mod model;
pub mod particle_array;
pub mod particles;
pub mod run_state;
pub mod sorted_grid;
pub mod time_step;
pub mod variant;

use crate::scene::setup::{calibrated_kernels, calibrated_mass, fastest_start_speed, rest_volume, InitialParticles};
use crate::scene::{DensityKernelKind, Pressure, Scene, ViscositySolver, ViscousVelocity, Walls};
use crate::simulation::dfsph_bender2017::PressureSolve;
use crate::simulation::host_particles::HostParticles;
use crate::simulation::inlet::Inlet;
use crate::simulation::model::{ImplicitStep, Model, ParticleState, SolveReport};
use crate::simulation::particles::Particles;
use crate::simulation::sorted_grid::SortedGrid;
use crate::simulation::time_step::{Cfl, Limit, StabilityBound, TimeStepper};
use backend::{Backend, ParticleViews, Passes, Schedule};
use coil_kernels::cell_grid::Neighbors;
use coil_kernels::continuity_molteni2009::{ContinuityArgs, DensityIntegrationArgs};
use coil_kernels::cross_viscosity::Rheology;
use coil_kernels::density::{DensityArgs, DensityKernel, Poly6, Spiky};
use coil_kernels::diagnostics::StateFigures;
use coil_kernels::fluid::Fluid;
use coil_kernels::leapfrog::LeapfrogArgs;
use coil_kernels::mirrored_wall::MirroredWallArgs;
use coil_kernels::nozzle::{NozzleArgs, NozzleShiftArgs};
use coil_kernels::shifting_sun2017::{ShiftArgs, Shifting, ShiftingArgs, LARGEST_SHIFT_SPACINGS};
use coil_kernels::topology::{Open, Topology};
use coil_kernels::{Real, Vec3};
pub use run_state::RunState;
use std::fmt;

/// The divergence of position, -sum_j V_j x_ij . grad W_ij, below which particle shifting takes
/// a particle to be near a free surface (3 inside the fluid, where the calibrated gradient makes
/// it exact on the lattice): DualSPHysics's threshold in 3-D.
const SURFACE_POSITION_DIVERGENCE: f64 = 2.75;

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

/// Figures of the state after a step, over fluid particles (see `coil_kernels::diagnostics`).
pub type Diagnostics = StateFigures;

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

/// A run on backend `B`: the run state, which every backend shares, and the particles, which
/// `B` holds.
pub struct Simulation<R: Real, M: Model<R>, B> {
    pub run: RunState<R, M>,
    pub backend: B,
}

/// A run's state and its particles in host memory, set up from a scene but not yet sorted: what
/// a backend starts from.
pub struct Setup<R: Real, M: Model<R>> {
    pub run: RunState<R, M>,
    pub host: HostParticles<R>,
    /// Each wall particle's mirror image (m), x, y, z by id, when walls mirror the fluid
    /// (`Walls::Mirrored`); not allocated otherwise.
    pub wall_mirror: Option<[Vec<f64>; 3]>,
}

impl<R: Real, M: Model<R>> Setup<R, M> {
    /// The run of `scene` with the particles `initial`.
    pub fn new(scene: &Scene, initial: &InitialParticles, model: M) -> Self {
        let mat = &scene.material;
        let h = scene.support_radius();
        let s = mat.particle_spacing_m;
        let mass = calibrated_mass(mat.rest_density_kg_m3, s, h, mat.density_kernel);
        let volume = rest_volume(scene, mass);
        let inlets: Vec<Inlet> = scene.inlets.iter().map(|c| Inlet::new(c, s, h, volume, mat.rest_density_kg_m3)).collect();
        let fluid_capacity = scene.simulation.max_fluid_particles.unwrap_or(0).max(initial.fluid.len());
        let boundary_count = initial.boundary.len();
        let kernels = calibrated_kernels::<R>(mat.rest_density_kg_m3, s, h, mat.density_kernel);
        let shifting = (scene.simulation.particle_shifting > 0.0).then(|| Shifting {
            coefficient: R::from_f64(scene.simulation.particle_shifting * h),
            inverse_spacing_weight: R::ONE / kernels.spiky(R::from_f64(s * s)),
            surface_divergence: R::from_f64(SURFACE_POSITION_DIVERGENCE),
            largest_shift: R::from_f64(LARGEST_SHIFT_SPACINGS * s),
        });
        let fields = M::FIELDS.with_scene(scene);
        let mut particles = Particles::with_capacity(boundary_count + fluid_capacity, fields);
        for (k, &x) in initial.boundary.iter().enumerate() {
            particles.push(k as u32, x, [0.0; 3]);
        }
        for (k, (&x, &v)) in initial.fluid.iter().zip(&initial.fluid_velocity).enumerate() {
            particles.push((boundary_count + k) as u32, x, v);
        }
        // The continuity equation starts every fluid particle at rest density; the sum sets
        // its own.
        let n = particles.len();
        particles.density[..n].fill(R::from_f64(mat.rest_density_kg_m3));
        let g = mat.gravity_m_s2;
        let divergence_free = scene.simulation.pressure == Pressure::DivergenceFree;
        // A solved pressure replaces Eq. (6): with c = 0 the acceleration pass adds none.
        let sound_speed2 = if divergence_free { 0.0 } else { mat.sound_speed_m_s * mat.sound_speed_m_s };
        let fluid = Fluid {
            mass: R::from_f64(mass),
            rest_density: R::from_f64(mat.rest_density_kg_m3),
            sound_speed2: R::from_f64(sound_speed2),
            pressure_floor: R::from_f64(if mat.clamp_negative_pressure { 0.0 } else { f64::NEG_INFINITY }),
            wall_density_floor: R::from_f64(if mat.clamp_negative_pressure { 0.0 } else { mat.rest_density_kg_m3 }),
            pressure_pair_weight: R::from_f64(mat.pressure_gradient.pair_weight()),
            wall_stiffness_share: R::from_f64(scene.simulation.divergence_free.wall_pressure.stiffness_share()),
            gravity: Vec3::from_f64(g),
            kernels,
            boundary_count: boundary_count as u32,
        };
        let ts = &scene.simulation.time_step;
        let bound =
            StabilityBound::new(h, mat.sound_speed_m_s, mat.viscosity.bounding_viscosity(model.law().max_viscosity().to_f64()));
        let df = scene.simulation.divergence_free;
        let stepper = TimeStepper {
            bound: if divergence_free { bound.incompressible() } else { bound },
            support_radius: h,
            safety_factor: ts.safety_factor,
            fixed: ts.fixed_s,
            cfl: divergence_free.then_some(Cfl { factor: df.cfl_factor, spacing_m: s, largest_s: df.max_time_step_s }),
        };
        let d = &scene.domain;
        let diagonal = (0..3).map(|a| (d.max_m[a] - d.min_m[a]).powi(2)).sum::<f64>().sqrt();
        let g_norm = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        let start_speed = fastest_start_speed(scene, initial);
        // A sound wave that compresses the fluid by 10 %, more than weakly compressible SPH
        // allows, moves it at 0.1 c; a full c let a run above the Eq. (10) bound throw
        // particles at 7 times the jet's fastest speed unstopped (docs/tradeoff.md).
        let runaway_speed = 2.0 * ((2.0 * g_norm * diagonal).sqrt() + start_speed) + 0.1 * mat.sound_speed_m_s;
        let run = RunState {
            fluid,
            model,
            inlets,
            stepper,
            time: 0.0,
            steps: 0,
            previous_dt: None,
            removed: 0,
            injected: 0,
            fluid_capacity,
            capacity_reached_at: None,
            fluid_count: initial.fluid.len(),
            next_id: (boundary_count + initial.fluid.len()) as u32,
            diagnostics: Diagnostics { max_speed: start_speed, ..Diagnostics::default() },
            runaway_speed,
            last_dt: 0.0,
            last_limit: Limit::Acoustic,
            density_kernel: mat.density_kernel,
            density_diffusivity: R::from_f64(mat.density_diffusion * 0.5 * h * mat.sound_speed_m_s),
            viscous_velocity: ts.viscous_velocity,
            shifting,
            implicit: (mat.viscosity.solver == ViscositySolver::Implicit).then_some(mat.viscosity.implicit),
            solves: Default::default(),
            pressure_solve: divergence_free.then_some(df),
            divergence_solves: Default::default(),
            density_solves: Default::default(),
        };
        let wall_mirror = (scene.simulation.walls == Walls::Mirrored)
            .then(|| [0, 1, 2].map(|a| initial.boundary_mirror.iter().map(|m| m[a]).collect()));
        let mut grid = SortedGrid::new(d.min_m, d.max_m, h, d.periodic);
        if wall_mirror.is_none() {
            grid.track_fluid(boundary_count as u32);
        }
        Self { run, host: HostParticles { particles, grid }, wall_mirror }
    }
}

impl<R: Real, M: Model<R>, B: Backend<R>> Simulation<R, M, B> {
    /// Algorithm 1, lines 3-8, once before the first step: the first sort and density, with
    /// the particle count read back and the host's particles current, for the first frame. The
    /// diagnostics keep the speed the fluid starts at, which the first dt reads.
    pub fn sort_and_density(&mut self) -> Result<(), B::Fault> {
        let removed = self.backend.sort_and_reorder()?;
        self.run.count_removed(removed);
        in_topology(&mut self.backend, DensityPass { run: &self.run })?;
        let readout = self.backend.read_diagnostics(self.run.fluid, 0.0)?;
        self.run.count_live(readout.live);
        self.backend.download()
    }

    /// dt for the next step and what limits it.
    pub fn next_dt(&self) -> (f64, Limit) {
        self.run.next_dt()
    }

    /// One step of Algorithm 1 with the automatic (or fixed) dt.
    pub fn step(&mut self) -> Result<(), StepError<B::Fault>> {
        let (dt, limit) = self.next_dt();
        self.step_with(dt, limit)
    }

    /// One step of Algorithm 1 with a given dt (s).
    pub fn step_with(&mut self, dt: f64, limit: Limit) -> Result<(), StepError<B::Fault>> {
        B::on_launch_thread(|| {
            // Line 1: inject.
            let (staging, room) = self.backend.inlet_staging();
            let added = self.run.inject(dt, room, staging);
            self.backend.append_staged(added).map_err(StepError::Backend)?;
            // Line 3: neighbors.
            let removed = self.backend.sort_and_reorder().map_err(StepError::Backend)?;
            self.run.count_removed(removed);
            // Lines 5-19: density and pressure, stress, accelerations, nozzles, leap-frog.
            let kick_dt = self.run.kick_dt(dt);
            let (mut solve, mut pressure_solves) = (None, None);
            let forces =
                ForcesAndMotion { run: &self.run, dt, kick_dt, solve: &mut solve, pressure_solves: &mut pressure_solves };
            in_topology(&mut self.backend, forces).map_err(StepError::Backend)?;
            self.run.advance_clock(dt, limit);
            if let Some(report) = solve {
                self.run.record_solve(report)?;
            }
            if let Some(reports) = pressure_solves {
                self.run.record_pressure_solves(reports)?;
            }
            if self.backend.diagnostics_due(self.run.steps) {
                self.read_diagnostics()?;
            }
            Ok(())
        })
    }

    /// Reads the diagnostics and the particle count; stops an unstable run.
    fn read_diagnostics(&mut self) -> Result<(), StepError<B::Fault>> {
        let runaway_speed2 = self.run.runaway_speed * self.run.runaway_speed;
        let readout = self.backend.read_diagnostics(self.run.fluid, runaway_speed2).map_err(StepError::Backend)?;
        self.run.record(readout);
        Ok(self.run.check()?)
    }

    /// Reads the diagnostics where the last step did not, and brings the host's particles up to
    /// date (before frames, at the end); stops an unstable run.
    pub fn sync(&mut self) -> Result<(), StepError<B::Fault>> {
        if !self.settled() {
            self.read_diagnostics()?;
        }
        self.backend.download().map_err(StepError::Backend)
    }

    /// The particles in host memory and their grid (current after [`Self::sync`]).
    pub fn host(&self) -> &HostParticles<R> {
        self.backend.host()
    }

    /// The particles in host memory, in their current order (current after [`Self::sync`]).
    pub fn particles(&self) -> &Particles<R> {
        &self.backend.host().particles
    }

    /// Whether the run state holds everything the next step reads (a device's figures and
    /// counts come back every few steps): where a stop may checkpoint the run, so that it
    /// resumes as if it had never stopped.
    pub fn settled(&self) -> bool {
        self.backend.diagnostics_due(self.run.steps)
    }
}

/// Runs `schedule` on `backend` in the domain's topology: the periodic neighbor loops only where
/// an axis wraps.
fn in_topology<R: Real, B: Backend<R>, S: Schedule<R>>(backend: &mut B, schedule: S) -> Result<(), B::Fault> {
    match backend.periodic() {
        Some(periodic) => backend.run(periodic, schedule),
        None => backend.run(Open, schedule),
    }
}

/// Algorithm 1, lines 5-8: density (pressure is evaluated from it where it is read), or, with
/// the continuity equation, the fluid's density rate and the walls' density; where pressure is
/// solved on the continuity density, the walls' density and the fluid's raised to its sum (the
/// density solve predicts the rate).
struct DensityPass<'r, R: Real, M: Model<R>> {
    run: &'r RunState<R, M>,
}

impl<R: Real, M: Model<R>> Schedule<R> for DensityPass<'_, R, M> {
    fn run<T: Topology, N: Neighbors, P: Passes<R, T, N>>(self, v: ParticleViews<'_, R, T, N>, passes: &mut P) {
        density(self.run, &v, passes);
    }
}

fn density<R: Real, M: Model<R>, T: Topology, N: Neighbors, P: Passes<R, T, N>>(
    run: &RunState<R, M>,
    v: &ParticleViews<'_, R, T, N>,
    passes: &mut P,
) {
    match run.density_kernel {
        DensityKernelKind::Poly6 => density_with::<R, M, Poly6, T, N, P>(run, v, passes),
        DensityKernelKind::Spiky => density_with::<R, M, Spiky, T, N, P>(run, v, passes),
    }
}

fn density_with<R: Real, M: Model<R>, K: DensityKernel, T: Topology, N: Neighbors, P: Passes<R, T, N>>(
    run: &RunState<R, M>,
    v: &ParticleViews<'_, R, T, N>,
    passes: &mut P,
) {
    let density_args = DensityArgs { neighborhood: v.neighbors, fluid: run.fluid, id: v.id, density: v.density };
    match v.density_rate {
        Some(_) if run.pressure_solve.is_some() => passes.continuity_floor(density_args),
        Some(density_rate) => passes.continuity::<K>(ContinuityArgs {
            neighborhood: v.neighbors,
            fluid: run.fluid,
            diffusivity: run.density_diffusivity,
            id: v.id,
            velocity: v.velocity.read(),
            density: v.density,
            density_rate,
        }),
        None => passes.density::<K>(density_args),
    }
}

/// Algorithm 1, lines 5-19: density, mirrored walls (when the scene asks), velocity gradient
/// and stress, accelerations, nozzles and leap-frog.
struct ForcesAndMotion<'r, R: Real, M: Model<R>> {
    run: &'r RunState<R, M>,
    /// This step (s).
    dt: f64,
    /// Leap-frog's kick (s).
    kick_dt: f64,
    /// How the implicit viscosity solve went, where there is one.
    solve: &'r mut Option<SolveReport>,
    /// How the divergence and density solves went, where pressure is solved.
    pressure_solves: &'r mut Option<[SolveReport; 2]>,
}

impl<R: Real, M: Model<R>> Schedule<R> for ForcesAndMotion<'_, R, M> {
    fn run<T: Topology, N: Neighbors, P: Passes<R, T, N>>(self, v: ParticleViews<'_, R, T, N>, passes: &mut P) {
        let run = self.run;
        let fluid = run.fluid;
        // Lines 5-8.
        density(run, &v, passes);
        let pressure_solve = run.pressure_solve.zip(v.pressure_solve).map(|(settings, arrays)| PressureSolve {
            settings,
            neighborhood: v.neighbors,
            fluid,
            dt: R::from_f64(self.dt),
            kick_dt: R::from_f64(self.kick_dt),
            id: v.id,
            position: v.position.read(),
            density: v.density.read(),
            velocity_half: v.velocity_half,
            acceleration: v.acceleration,
            continuity: v.density_rate.is_some(),
            arrays,
            inlets: run.inlets(),
            time: run.time,
        });
        let divergence = pressure_solve.as_ref().map(|solve| {
            solve.factors(passes);
            solve.divergence(passes)
        });
        let viscous_velocity = match run.viscous_velocity {
            ViscousVelocity::FullStep => v.velocity,
            ViscousVelocity::HalfStep => v.velocity_half,
        };
        if let Some(mirror) = v.wall_mirror {
            passes.mirrored_wall(MirroredWallArgs {
                neighborhood: v.grid,
                fluid,
                id: v.id,
                mirror,
                velocity: viscous_velocity,
                density: v.density,
            });
        }
        // Lines 9-16: velocity gradient and stress, accelerations.
        *self.solve = run.model.accelerations(
            passes,
            ParticleState {
                neighborhood: v.neighbors,
                fluid,
                id: v.id,
                velocity: viscous_velocity.read(),
                density: v.density.read(),
                stress: v.stress,
                viscosity: v.viscosity,
                velocity_gradient: v.velocity_gradient,
                acceleration: v.acceleration,
                implicit: v.implicit.map(|arrays| ImplicitStep {
                    kick_dt: R::from_f64(self.kick_dt),
                    velocity_half: v.velocity_half.read(),
                    velocity: viscous_velocity.read(),
                    arrays,
                    position: v.position.read(),
                    inlets: run.inlets(),
                    time: run.time,
                }),
            },
        );
        // Fluid inside a nozzle's tube moves with the jet (paper Sec. III-C; see `nozzle`).
        for tube in run.inlet_tubes() {
            passes.nozzle(NozzleArgs {
                fluid,
                tube,
                id: v.id,
                position: v.position.read(),
                acceleration: v.acceleration,
                velocity_half: v.velocity_half,
            });
        }
        // Pressure last: the density the step ends at counts gravity and viscosity.
        if let (Some(solve), Some(divergence)) = (&pressure_solve, divergence) {
            *self.pressure_solves = Some([divergence, solve.density(passes)]);
        }
        // The continuity equation's density after the accelerations have read this step's;
        // where pressure is solved, the density the solve predicted.
        if let Some(density_rate) = v.density_rate {
            if let Some(solve) = &pressure_solve {
                solve.density_rate(passes, density_rate);
            }
            passes.density_integration(DensityIntegrationArgs {
                fluid,
                dt: R::from_f64(self.dt),
                id: v.id,
                density_rate: density_rate.read(),
                density: v.density,
            });
        }
        // Shifts over this step's positions, which leap-frog is about to move.
        let shift = v.shift.zip(run.shifting);
        if let Some((shift, shifting)) = shift {
            passes.shifting(ShiftingArgs {
                neighborhood: v.neighbors,
                fluid,
                shifting,
                dt: R::from_f64(self.dt),
                id: v.id,
                velocity: v.velocity.read(),
                shift,
            });
            for tube in run.inlet_tubes() {
                passes.nozzle_shift(NozzleShiftArgs { fluid, tube, id: v.id, position: v.position.read(), shift });
            }
        }
        // Lines 17-19: leap-frog.
        passes.leapfrog(LeapfrogArgs {
            fluid,
            dt: R::from_f64(self.dt),
            kick_dt: R::from_f64(self.kick_dt),
            id: v.id,
            acceleration: v.acceleration.read(),
            position: v.position,
            velocity_half: v.velocity_half,
            velocity: v.velocity,
            topology: v.topology,
        });
        if let Some((shift, _)) = shift {
            passes.shift(ShiftArgs { topology: v.topology, shift: shift.read(), position: v.position });
        }
    }
}
