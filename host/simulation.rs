//! One run: the particle state, the neighbor grid and the physics variant, advanced step by
//! step through Algorithm 1 on the CPU.

use crate::inlet::Inlet;
use crate::model::{CpuPasses, Model, ParticleState};
use crate::neighbor_grid::NeighborGrid;
use crate::parallel::{launch, on_worker};
use crate::particles::{mat3_view_mut, stress_view_mut, vec3_view, vec3_view_mut, view_mut, Particles};
use crate::scene::{DensityKernel, Scene, ViscousVelocity, Walls};
use crate::setup::{calibrated_kernels, calibrated_mass, fastest_start_speed, InitialParticles};
use crate::time_step::{Limit, StabilityBound, TimeStepper};
use coil_kernels::cell_grid::Neighbors;
use coil_kernels::density::{density_pass, DensityArgs, Poly6, Spiky};
use coil_kernels::diagnostics::{range_figures, DiagnosticsArgs, StateFigures};
use coil_kernels::fluid::Fluid;
use coil_kernels::leapfrog::{leapfrog_pass, LeapfrogArgs};
use coil_kernels::mirrored_wall::{mirrored_wall_pass, MirroredWallArgs};
use coil_kernels::nozzle::{nozzle_pass, NozzleArgs, NozzleTube};
use coil_kernels::topology::{Open, Periodic, Topology};
use coil_kernels::view::{Vec3View, View};
use coil_kernels::{Real, Vec3};
use rayon::prelude::*;
use std::fmt;

/// Why a run stopped early.
#[derive(Debug, Clone, PartialEq)]
pub struct Instability {
    pub step: u64,
    pub time_s: f64,
    /// Fluid particles with a non-finite velocity or a speed above the runaway limit.
    pub bad_particles: usize,
    pub max_speed_m_s: f64,
    pub runaway_speed_m_s: f64,
    pub dt_s: f64,
    pub stability_bound_s: f64,
    /// The velocity the viscous terms read.
    pub viscous_velocity: ViscousVelocity,
}

impl fmt::Display for Instability {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the run went unstable at step {} (t = {:.6e} s): {} particle(s) with a non-finite velocity or a speed above {:.3} m/s (largest finite speed {:.3e} m/s). ",
            self.step, self.time_s, self.bad_particles, self.runaway_speed_m_s, self.max_speed_m_s
        )?;
        if self.dt_s > self.stability_bound_s {
            write!(
                f,
                "Likely cause: dt = {:.3e} s is above the Eq. (10) bound {:.3e} s; lower simulation.time_step.fixed_s or safety_factor (the README gives how far above the bound each viscosity operator was measured to stay stable).",
                self.dt_s, self.stability_bound_s
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

/// Particles per range of the diagnostics reduction.
const DIAGNOSTICS_RANGE: usize = 1024;

pub struct Simulation<R: Real, M: Model<R>> {
    pub particles: Particles<R>,
    pub(crate) grid: NeighborGrid,
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
    fluid_capacity: usize,
    /// When (s) an inlet first had a layer due that the fluid capacity could not take; from
    /// then on the jets run only as particles leave the domain.
    pub capacity_reached_at: Option<f64>,
    fluid_count: usize,
    pub(crate) next_id: u32,
    /// Largest fluid speed after the last step (m/s), which the velocity CFL reads.
    pub diagnostics: Diagnostics,
    /// A speed no particle can reach physically (m/s): twice the free fall across the domain
    /// plus the fastest jet, plus 0.1 c.
    pub runaway_speed: f64,
    pub last_dt: f64,
    pub last_limit: Limit,
    /// Each wall particle's mirror image (m), x, y, z by id, when walls mirror the fluid
    /// (`Walls::Mirrored`); not allocated otherwise.
    pub wall_mirror: Option<[Vec<f64>; 3]>,
    /// The kernel of Eq. (5): which monomorphised density pass each step launches.
    pub density_kernel: DensityKernel,
    /// Which velocity the viscous terms read.
    pub viscous_velocity: ViscousVelocity,
}

impl<R: Real, M: Model<R>> Simulation<R, M> {
    /// Sets up a run of `scene` with the particles `initial` on the CPU backend.
    pub fn new(scene: &Scene, initial: &InitialParticles, model: M) -> Self {
        Self::for_backend(scene, initial, model, false)
    }

    /// Sets up a run for a device backend: the host keeps no neighbor lists, and its own
    /// passes (the setup's density, and the steps of an operation count, which counts the
    /// device's work) visit neighbors through the grid as the device does.
    pub fn for_device(scene: &Scene, initial: &InitialParticles, model: M) -> Self {
        Self::for_backend(scene, initial, model, true)
    }

    /// [`Self::for_device`] where `on_device`, else [`Self::new`].
    pub fn for_backend(scene: &Scene, initial: &InitialParticles, model: M, on_device: bool) -> Self {
        let mat = &scene.material;
        let h = scene.support_radius();
        let s = mat.particle_spacing_m;
        let mass = calibrated_mass(mat.rest_density_kg_m3, s, h, mat.density_kernel);
        let inlets: Vec<Inlet> = scene.inlets.iter().map(|c| Inlet::new(c, s, h, mass, mat.rest_density_kg_m3)).collect();
        let fluid_capacity = scene.simulation.max_fluid_particles.unwrap_or(0).max(initial.fluid.len());
        let boundary_count = initial.boundary.len();
        let mut particles = Particles::with_capacity(boundary_count + fluid_capacity, M::FIELDS);
        for (k, &x) in initial.boundary.iter().enumerate() {
            particles.push(k as u32, x, [0.0; 3]);
        }
        for (k, (&x, &v)) in initial.fluid.iter().zip(&initial.fluid_velocity).enumerate() {
            particles.push((boundary_count + k) as u32, x, v);
        }
        let g = mat.gravity_m_s2;
        let fluid = Fluid {
            mass: R::from_f64(mass),
            rest_density: R::from_f64(mat.rest_density_kg_m3),
            sound_speed2: R::from_f64(mat.sound_speed_m_s * mat.sound_speed_m_s),
            pressure_floor: R::from_f64(if mat.clamp_negative_pressure { 0.0 } else { f64::NEG_INFINITY }),
            pressure_pair_weight: R::from_f64(mat.pressure_gradient.pair_weight()),
            gravity: Vec3::from_f64(g),
            kernels: calibrated_kernels(mat.rest_density_kg_m3, s, h, mat.density_kernel),
            boundary_count: boundary_count as u32,
        };
        let ts = &scene.simulation.time_step;
        let stepper = TimeStepper {
            bound: StabilityBound::new(h, mat.sound_speed_m_s, model.max_viscosity().to_f64()),
            support_radius: h,
            safety_factor: ts.safety_factor,
            fixed: ts.fixed_s,
        };
        let d = &scene.domain;
        let diagonal = (0..3).map(|a| (d.max_m[a] - d.min_m[a]).powi(2)).sum::<f64>().sqrt();
        let g_norm = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        let start_speed = fastest_start_speed(scene, initial);
        // A sound wave that compresses the fluid by 10 %, more than weakly compressible SPH
        // allows, moves it at 0.1 c; a full c let a run above the Eq. (10) bound throw
        // particles at 7 times the jet's fastest speed unstopped (README, Trade-off).
        let runaway_speed = 2.0 * ((2.0 * g_norm * diagonal).sqrt() + start_speed) + 0.1 * mat.sound_speed_m_s;
        let mut sim = Self {
            particles,
            grid: NeighborGrid::new(d.min_m, d.max_m, h, d.periodic, boundary_count + fluid_capacity),
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
            diagnostics: Diagnostics::default(),
            runaway_speed,
            last_dt: 0.0,
            last_limit: Limit::Acoustic,
            wall_mirror: (scene.simulation.walls == Walls::Mirrored)
                .then(|| [0, 1, 2].map(|a| initial.boundary_mirror.iter().map(|m| m[a]).collect())),
            density_kernel: mat.density_kernel,
            viscous_velocity: ts.viscous_velocity,
        };
        if sim.wall_mirror.is_none() {
            sim.grid.track_fluid(fluid.boundary_count);
        }
        if !on_device {
            sim.grid.keep_neighbor_lists();
        }
        sim.sort_and_density();
        sim.diagnostics.max_speed = start_speed;
        sim
    }

    /// Fluid particles now in the run.
    pub fn fluid_count(&self) -> usize {
        self.fluid_count
    }

    pub fn boundary_count(&self) -> usize {
        self.fluid.boundary_count as usize
    }

    /// Bytes of particle and grid memory the run allocated.
    pub fn memory_bytes(&self) -> usize {
        let mirror = self.wall_mirror.as_ref().map_or(0, |m| 3 * m[0].len() * std::mem::size_of::<f64>());
        self.particles.capacity() * self.particles.bytes_per_particle() + self.grid.bytes() + mirror
    }

    /// The neighbor grid of the particles' current order (valid after a step), with the
    /// domain's periods (none for an open domain). For output and checks; the step's own passes
    /// take the open or periodic loop by type.
    pub fn neighborhood(&self) -> coil_kernels::cell_grid::Neighborhood<'_, Periodic> {
        self.grid.neighborhood(self.particles.position_view(), self.grid.periodic)
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

    /// One step of Algorithm 1 with the automatic (or fixed) dt.
    pub fn step(&mut self) -> Result<(), Instability> {
        let (dt, limit) = self.next_dt();
        self.step_with(dt, limit)
    }

    /// One step of Algorithm 1 with a given dt (s).
    pub fn step_with(&mut self, dt: f64, limit: Limit) -> Result<(), Instability> {
        on_worker(|| self.step_on_worker(dt, limit))
    }

    fn step_on_worker(&mut self, dt: f64, limit: Limit) -> Result<(), Instability> {
        // Line 1: inject.
        let room = self.fluid_capacity - self.fluid_count;
        let added = inject(&mut self.inlets, self.time, dt, room, &mut self.next_id, &mut self.particles);
        self.count_injected(added);
        self.sort_and_density();
        if self.grid.is_periodic() {
            self.forces_and_motion(self.grid.periodic, dt);
        } else {
            self.forces_and_motion(Open, dt);
        }
        self.advance_clock(dt, limit);
        self.diagnostics = self.measure();
        self.check()
    }

    /// Algorithm 1, line 3: neighbors, dropping particles that left the domain, and their
    /// lists where the run keeps them; lines 5-8: density (pressure is evaluated from it where
    /// it is read).
    fn sort_and_density(&mut self) {
        let removed = self.grid.sort(&mut self.particles);
        self.count_removed(removed);
        if self.grid.is_periodic() {
            self.density(self.grid.periodic);
        } else {
            self.density(Open);
        }
    }

    fn density<T: Topology>(&mut self, topology: T) {
        let p = &mut self.particles;
        let n = p.len();
        let position = vec3_view(&p.position, n);
        self.grid.record_neighbors(position, self.fluid.kernels.h2, topology);
        let grid = &self.grid;
        let density = view_mut(&mut p.density, n);
        if grid.keeps_neighbor_lists() {
            let neighborhood = grid.listed_neighborhood(position, topology);
            density_passes(self.density_kernel, n, DensityArgs { neighborhood, fluid: self.fluid, density });
        } else {
            let neighborhood = grid.neighborhood(position, topology);
            density_passes(self.density_kernel, n, DensityArgs { neighborhood, fluid: self.fluid, density });
        }
    }

    /// Algorithm 1, lines 9-19, after the density: mirrored walls (when asked), stress,
    /// accelerations, nozzles and leap-frog, with the neighbor loops of topology `T`.
    fn forces_and_motion<T: Topology>(&mut self, topology: T, dt: f64) {
        let kick_dt = self.kick_dt(dt);
        let p = &mut self.particles;
        let n = p.len();
        if let Some(mirror) = &self.wall_mirror {
            let velocity = match self.viscous_velocity {
                ViscousVelocity::FullStep => &mut p.velocity,
                ViscousVelocity::HalfStep => &mut p.velocity_half,
            };
            let args = MirroredWallArgs {
                neighborhood: self.grid.neighborhood(vec3_view(&p.position, n), topology),
                fluid: self.fluid,
                id: View::new(&p.id[..n]),
                mirror: Vec3View::new(&mirror[0], &mirror[1], &mirror[2]),
                velocity: vec3_view_mut(velocity, n),
                density: view_mut(&mut p.density, n),
            };
            launch(n, |i| mirrored_wall_pass(i, &args));
        }
        // Lines 9-16: velocity gradient and stress, accelerations.
        let (grid, read) = (&self.grid, self.viscous_velocity);
        if grid.keeps_neighbor_lists() {
            accelerations(&self.model, self.fluid, p, read, |position| grid.listed_neighborhood(position, topology));
        } else {
            accelerations(&self.model, self.fluid, p, read, |position| grid.neighborhood(position, topology));
        }
        // Fluid inside a nozzle's tube moves with the jet (paper Sec. III-C; see `nozzle`).
        for inlet in &self.inlets {
            let args = NozzleArgs {
                fluid: self.fluid,
                tube: inlet.tube(self.time),
                id: View::new(&p.id[..n]),
                position: vec3_view(&p.position, n),
                acceleration: vec3_view_mut(&mut p.acceleration, n),
                velocity_half: vec3_view_mut(&mut p.velocity_half, n),
            };
            launch(n, |i| nozzle_pass(i, &args));
        }
        // Lines 17-19: leap-frog.
        {
            let args = LeapfrogArgs {
                fluid: self.fluid,
                dt: R::from_f64(dt),
                kick_dt: R::from_f64(kick_dt),
                id: View::new(&p.id[..n]),
                acceleration: vec3_view(&p.acceleration, n),
                position: vec3_view_mut(&mut p.position, n),
                velocity_half: vec3_view_mut(&mut p.velocity_half, n),
                velocity: vec3_view_mut(&mut p.velocity, n),
                topology,
            };
            launch(n, |i| leapfrog_pass(i, &args));
        }
    }

    /// Counts the particles an injection added, and notes when the inlets first found the
    /// fluid capacity full.
    pub(crate) fn count_injected(&mut self, added: usize) {
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

    /// The guard: the latest diagnostics must show no runaway particle.
    pub(crate) fn check(&self) -> Result<(), Instability> {
        if self.diagnostics.bad_particles == 0 {
            return Ok(());
        }
        Err(Instability {
            step: self.steps,
            time_s: self.time,
            bad_particles: self.diagnostics.bad_particles as usize,
            max_speed_m_s: self.diagnostics.max_speed,
            runaway_speed_m_s: self.runaway_speed,
            dt_s: self.last_dt,
            stability_bound_s: self.stepper.bound.dt().0,
            viscous_velocity: self.viscous_velocity,
        })
    }

    /// Largest speed and compression over the fluid, and how many fluid particles run away.
    pub fn measure(&self) -> Diagnostics {
        let p = &self.particles;
        let n = p.len();
        let args = self.diagnostics_args();
        (0..n.div_ceil(DIAGNOSTICS_RANGE))
            .into_par_iter()
            .map(|r| range_figures(r, DIAGNOSTICS_RANGE, n, &args))
            .reduce(Diagnostics::default, Diagnostics::combine)
    }

    /// The diagnostics pass's arguments for the host particles.
    fn diagnostics_args(&self) -> DiagnosticsArgs<'_, R> {
        let p = &self.particles;
        DiagnosticsArgs {
            fluid: self.fluid,
            runaway_speed2: self.runaway_speed * self.runaway_speed,
            id: p.id_view(),
            velocity: p.velocity_view(),
            density: p.density_view(),
        }
    }
}

/// Algorithm 1, line 1: every inlet appends the layers due after `dt` from `time` to `p`,
/// within `room` particles in all. Returns how many it added.
pub(crate) fn inject<R: Real>(
    inlets: &mut [Inlet],
    time: f64,
    dt: f64,
    room: usize,
    next_id: &mut u32,
    p: &mut Particles<R>,
) -> usize {
    let mut added = 0;
    for inlet in inlets {
        added += inlet.inject(time, dt, room - added, next_id, p);
    }
    added
}

/// The density pass over `n` particles with the density kernel `kernel`.
fn density_passes<R: Real, N: Neighbors + Sync>(kernel: DensityKernel, n: usize, args: DensityArgs<R, N>) {
    match kernel {
        DensityKernel::Poly6 => launch(n, |i| density_pass::<R, Poly6, N>(i, &args)),
        DensityKernel::Spiky => launch(n, |i| density_pass::<R, Spiky, N>(i, &args)),
    }
}

/// The model's passes over the particles `p`, visiting neighbors through what `neighborhood`
/// builds over their positions, with the viscous terms reading the velocity `read`.
fn accelerations<'a, R: Real, M: Model<R>, N: Neighbors + Sync>(
    model: &M,
    fluid: Fluid<R>,
    p: &'a mut Particles<R>,
    read: ViscousVelocity,
    neighborhood: impl FnOnce(Vec3View<'a, f64>) -> N,
) {
    let n = p.len();
    let velocity = match read {
        ViscousVelocity::FullStep => &p.velocity,
        ViscousVelocity::HalfStep => &p.velocity_half,
    };
    let state = ParticleState {
        neighborhood: neighborhood(vec3_view(&p.position, n)),
        fluid,
        id: View::new(&p.id[..n]),
        velocity: vec3_view(velocity, n),
        density: View::new(&p.density[..n]),
        stress: p.stress.as_mut().map(|s| stress_view_mut(s, n)),
        viscosity: p.viscosity.as_mut().map(|v| view_mut(v, n)),
        velocity_gradient: p.velocity_gradient.as_mut().map(|g| mat3_view_mut(g, n)),
        acceleration: vec3_view_mut(&mut p.acceleration, n),
    };
    model.accelerations(&mut CpuPasses { n }, state);
}
