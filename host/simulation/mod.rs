//! One run: the backend-neutral run state and a backend's particles, advanced step by step
//! through Algorithm 1 by one schedule that every backend runs.

pub mod backend;
pub mod carried_state;
pub mod cell_sort;
pub mod dfsph_bender2017;
pub mod host_particles;
pub mod implicit_weiler2018;
pub mod instability;
pub mod model;
pub mod particle_array;
pub mod particles;
pub(crate) mod pass_table;
pub mod run_state;
mod schedule;
pub mod sorted_grid;
pub mod variant;

use crate::scene::inlet::Inlet;
use crate::scene::setup::{calibrated_kernels, calibrated_mass, fastest_start_speed, rest_volume, InitialParticles};
use crate::scene::{Pressure, Scene, ViscositySolver, Walls};
use crate::simulation::host_particles::HostParticles;
use crate::simulation::model::Model;
use crate::simulation::particles::Particles;
use crate::simulation::sorted_grid::SortedGrid;
use crate::time_step::{Cfl, Limit, StabilityBound, TimeStepper};
use backend::Backend;
use coil_kernels::cross_viscosity::Rheology;
use coil_kernels::diagnostics::StateFigures;
use coil_kernels::fluid::Fluid;
use coil_kernels::shifting_sun2017::{Shifting, LARGEST_SHIFT_SPACINGS};
use coil_kernels::{Real, Vec3};
pub use instability::{Instability, Solve, StepError, UnconvergedSolve};
pub use run_state::RunState;
use schedule::{in_topology, DensityPass, ForcesAndMotion};

/// The divergence of position, -sum_j V_j x_ij . grad W_ij, below which particle shifting takes
/// a particle to be near a free surface (3 inside the fluid, where the calibrated gradient makes
/// it exact on the lattice): DualSPHysics's threshold in 3-D.
const SURFACE_POSITION_DIVERGENCE: f64 = 2.75;

/// Figures of the state after a step, over fluid particles (see `coil_kernels::diagnostics`).
pub type Diagnostics = StateFigures;

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
