//! `coil check`: what a scene will cost before it runs. Counts, h, the Eq. (10) bound and its
//! limiting term, memory, and a wall-time estimate from a short calibration run on this machine.

use crate::cpu::simulation::CpuSimulation;
use crate::scene::inlet::Inlet;
use crate::scene::setup::{initial_particles, InitialParticles};
use crate::scene::{Boundary, Domain, FluidBlock, Precision, Pressure, Scene, SceneError};
use crate::simulation::backend::Backend as _;
use crate::simulation::model::Model;
use crate::simulation::variant::{with_precision_and_model, WithModel};
#[cfg(feature = "cuda")]
use crate::simulation::Setup;
use crate::time_step::{Limit, StabilityBound, TimeStepper};
use coil_kernels::Real;
use std::fmt;
use std::time::{Duration, Instant};

/// What `coil check` prints.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    pub initial_fluid: usize,
    pub boundary: usize,
    /// Fluid capacity: the initial fluid plus everything inlets may inject.
    pub fluid_capacity: usize,
    /// Particles per second from all inlets while they run.
    pub inlet_rate: f64,
    /// Fluid particles at the end time, from the inlet rates and the budget.
    pub final_fluid: usize,
    /// When the fluid capacity fills and stops the inlets (s), and the capacity the end time
    /// would need; `None` where it does not fill.
    pub capacity_full: Option<(f64, usize)>,
    pub spacing_m: f64,
    pub support_radius_m: f64,
    /// The fastest the fluid can move without viscosity (m/s), and over c; `None` where
    /// gravity runs along a periodic axis, which it can fall along forever.
    pub speed_bound_m_s: Option<f64>,
    pub mach_bound: Option<f64>,
    pub bound: StabilityBound,
    /// dt the run will take (s) and what limits it; the velocity CFL may lower it further when a
    /// particle moves faster than c.
    pub dt_s: f64,
    pub limit: Limit,
    pub steps: f64,
    pub memory_bytes: usize,
    /// Device memory of the same run on the CUDA backend (bytes), in builds that have it.
    pub device_memory_bytes: Option<usize>,
    pub precision: Precision,
    pub threads: usize,
    /// Measured cost of one particle through one step (s), from the calibration run.
    pub seconds_per_particle_step: f64,
    pub calibration_steps: u64,
    /// Particle-steps of the whole run, boundary included.
    pub particle_steps: f64,
    pub estimated_wall_s: f64,
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mib = self.memory_bytes as f64 / (1024.0 * 1024.0);
        writeln!(f, "particles          {} fluid at t = 0, {} boundary", self.initial_fluid, self.boundary)?;
        if self.inlet_rate > 0.0 {
            writeln!(f, "inlets             {:.0} particles/s, {} fluid at the end time", self.inlet_rate, self.final_fluid)?;
        }
        writeln!(f, "capacity           {} fluid (simulation.max_fluid_particles)", self.fluid_capacity)?;
        if let Some((t, needed)) = self.capacity_full {
            writeln!(
                f,
                "warning            the capacity fills at t = {t:.3} s and stops the inlets; the end time needs about {needed} (raise simulation.max_fluid_particles)"
            )?;
        }
        writeln!(f, "spacing, h         {} m, {} m", self.spacing_m, self.support_radius_m)?;
        match (self.speed_bound_m_s, self.mach_bound) {
            (Some(speed), Some(mach)) => writeln!(
                f,
                "speed, Mach        at most {speed:.3} m/s (the fastest start, plus free fall through the domain), Mach {mach:.3}"
            )?,
            _ => writeln!(f, "speed, Mach        bounded only by viscosity: gravity runs along a periodic axis")?,
        }
        if self.mach_bound.is_some_and(|mach| mach > 1.0) {
            writeln!(
                f,
                "warning            above Mach 1 falling fluid compresses far past its rest density and can pass through walls; raise material.sound_speed_m_s (Mach 0.1 or less for quantitative runs)"
            )?;
        }
        // An implicit viscosity solve leaves the viscous term unbounded.
        let viscous = if self.bound.viscous_s.is_finite() {
            format!("viscous 0.1 h^2/(8 nu0) = {:.3e} s", self.bound.viscous_s)
        } else {
            "viscous: none (solved implicitly)".to_string()
        };
        let acoustic = if self.bound.acoustic_s.is_finite() {
            format!("acoustic 0.1 h/c = {:.3e} s", self.bound.acoustic_s)
        } else {
            "acoustic: none (pressure solved)".to_string()
        };
        let bound = self.bound.dt().0;
        let bound = if bound.is_finite() { format!("{bound:.3e} s") } else { "none".to_string() };
        writeln!(f, "Eq. (10) bound     {bound}: {acoustic}, {viscous}")?;
        writeln!(f, "dt                 {:.3e} s, limited by the {}", self.dt_s, self.limit)?;
        writeln!(f, "steps              {:.0}", self.steps)?;
        writeln!(f, "memory             {mib:.1} MiB of particle and grid arrays ({:?})", self.precision)?;
        if let Some(bytes) = self.device_memory_bytes {
            writeln!(f, "device memory      {:.1} MiB with --backend cuda", bytes as f64 / (1024.0 * 1024.0))?;
        }
        writeln!(
            f,
            "calibration        {:.3e} s per particle-step over {} steps on {} thread(s)",
            self.seconds_per_particle_step, self.calibration_steps, self.threads
        )?;
        write!(
            f,
            "estimated wall     {} for {:.3e} particle-steps on this machine",
            human(self.estimated_wall_s),
            self.particle_steps
        )
    }
}

/// The fastest a fluid particle can move (m/s) (`Scene::fastest_speed`); `None` where
/// gravity runs along a periodic axis, which bounds the fall by viscosity only.
fn speed_bound(scene: &Scene) -> Option<f64> {
    let (g, d) = (scene.material.gravity_m_s2, &scene.domain);
    if (0..3).any(|a| d.periodic[a] && g[a] != 0.0) {
        return None;
    }
    Some(scene.fastest_speed())
}

fn human(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

/// Fluid particles at time `t` (s): the initial fluid plus what the inlets delivered, up to the
/// capacity (inlets inject whole layers up to it).
fn fluid_at(t: f64, initial: usize, capacity: usize, inlets: &[Inlet]) -> f64 {
    let injected: f64 = inlets
        .iter()
        .map(|i| {
            let (start, stop) = i.active();
            i.particles_per_second() * (t.min(stop) - start).max(0.0)
        })
        .sum();
    (initial as f64 + injected).min(capacity as f64)
}

/// When the inlets fill `capacity` (s), and the fluid the end time `end` (s) would need, where
/// they fill it before the end.
fn capacity_full(end: f64, initial: usize, capacity: usize, inlets: &[Inlet]) -> Option<(f64, usize)> {
    let needed = fluid_at(end, initial, usize::MAX, inlets);
    if needed <= capacity as f64 {
        return None;
    }
    // The delivered fluid only grows with time: bisect for the moment it reaches the capacity.
    let (mut before, mut after) = (0.0, end);
    for _ in 0..60 {
        let t = 0.5 * (before + after);
        if fluid_at(t, initial, usize::MAX, inlets) < capacity as f64 {
            before = t;
        } else {
            after = t;
        }
    }
    Some((after, needed.ceil() as usize))
}

/// `scene`'s material in a closed box filled with a cube of about `fluid` particles at rest.
fn fluid_box(scene: &Scene, fluid: f64) -> Scene {
    let s = scene.material.particle_spacing_m;
    // The cost of a particle-step hardly changes past a few thousand particles; a larger box
    // would only make the calibration outlast the time it was given.
    let edge = fluid.clamp(1000.0, 100_000.0).cbrt().ceil() * s;
    let pad = 2.0 * scene.support_radius() + s;
    let mut proxy = scene.clone();
    proxy.inlets.clear();
    proxy.boundaries = vec![Boundary::Box { min_m: [0.0; 3], max_m: [edge; 3], open_top: false }];
    proxy.fluid_blocks = vec![FluidBlock { min_m: [0.0; 3], max_m: [edge; 3], velocity_m_s: [0.0; 3] }];
    proxy.domain = Domain { min_m: [-pad; 3], max_m: [edge + pad; 3], periodic: [false; 3] };
    proxy.simulation.max_fluid_particles = None;
    proxy
}

struct Calibrate<'a> {
    scene: &'a Scene,
    initial: &'a InitialParticles,
    wall: Duration,
}

impl WithModel for Calibrate<'_> {
    /// (seconds per particle-step, steps taken)
    type Output = (f64, u64);
    fn with<R: Real, M: Model<R>>(self, model: M) -> Self::Output {
        let mut sim = CpuSimulation::<R, M>::new(self.scene, self.initial, model);
        let started = Instant::now();
        let mut particle_steps = 0.0;
        // Stop at the first instability too: a scene's cost is still worth reporting.
        while (sim.run.steps < 2 || started.elapsed() < self.wall) && sim.run.steps < 10_000 && sim.step().is_ok() {
            particle_steps += sim.particles().len() as f64;
        }
        let seconds = started.elapsed().as_secs_f64();
        (if particle_steps > 0.0 { seconds / particle_steps } else { 0.0 }, sim.run.steps)
    }
}

/// What a run of the scene will be, read off a run set up as `coil run` sets it up.
struct RunPlan {
    inlets: Vec<Inlet>,
    fluid_capacity: usize,
    stepper: TimeStepper,
    memory_bytes: usize,
    device_memory_bytes: Option<usize>,
}

struct Plan<'a> {
    scene: &'a Scene,
    initial: &'a InitialParticles,
}

impl WithModel for Plan<'_> {
    type Output = RunPlan;
    fn with<R: Real, M: Model<R>>(self, model: M) -> Self::Output {
        let sim = CpuSimulation::<R, M>::new(self.scene, self.initial, model);
        let run = &sim.run;
        let (inlets, fluid_capacity, stepper, memory_bytes) =
            (run.inlets().to_vec(), run.fluid_capacity(), run.stepper, sim.backend.memory_bytes());
        // Counted by allocating it on the emulated device, whose memory is the host's: the
        // figure `coil run --backend cuda` prints, with no GPU needed.
        #[cfg(feature = "cuda")]
        let device_memory_bytes =
            crate::cuda::GpuSimulation::on_gpu(Setup::new(self.scene, self.initial, model), crate::cuda::Gpu::emulated())
                .ok()
                .map(|g| g.backend.memory_bytes());
        #[cfg(not(feature = "cuda"))]
        let device_memory_bytes = None;
        RunPlan { inlets, fluid_capacity, stepper, memory_bytes, device_memory_bytes }
    }
}

/// Checks `scene` and measures its cost for `calibration` of wall time.
pub fn check(scene: &Scene, file: &str, precision: Option<Precision>, calibration: Duration) -> Result<Report, SceneError> {
    let precision = precision.unwrap_or(scene.simulation.precision);
    scene.check_precision(precision, file)?;
    let initial = initial_particles(scene, file)?;
    // The run as `coil run` sets it up: its inlets, capacity, time stepper and memory.
    let plan = with_precision_and_model(precision, scene, Plan { scene, initial: &initial });
    let (inlets, capacity) = (&plan.inlets, plan.fluid_capacity);
    // Eq. (10) from the scene's own f64 values: an f32 run rounds nu0 first, which moves its
    // bound in the eighth digit.
    let v = &scene.material.viscosity;
    let bound = StabilityBound::new(
        scene.support_radius(),
        scene.material.sound_speed_m_s,
        v.bounding_viscosity(v.nu0_m2_s.max(v.nu_inf())),
    );
    // Solved pressure has no acoustic term, and its CFL step is estimated at the fastest speed
    // the run can reach.
    let divergence_free = scene.simulation.pressure == Pressure::DivergenceFree;
    let bound = if divergence_free { bound.incompressible() } else { bound };
    let speed_bound = speed_bound(scene);
    let fastest = if divergence_free { speed_bound.unwrap_or(0.0) } else { 0.0 };
    let (dt, limit) = TimeStepper { bound, ..plan.stepper }.next(fastest);
    let end = scene.simulation.end_time_s;
    let steps = (end / dt).ceil();
    // Particle-steps over the run, the fluid count integrated over time.
    let samples = 200;
    let mean_fluid = (0..samples)
        .map(|k| fluid_at((k as f64 + 0.5) * end / samples as f64, initial.fluid.len(), capacity, inlets))
        .sum::<f64>()
        / samples as f64;
    let particle_steps = steps * (initial.boundary.len() as f64 + mean_fluid);
    // A jet scene starts with no fluid, and walls with empty neighborhoods cost a fraction of a
    // fluid particle: calibrate it on a box of the run's mean fluid count instead.
    let (proxy, proxy_initial);
    let (calibrated_scene, calibrated_initial) = if (initial.fluid.len() as f64) < 0.5 * mean_fluid {
        proxy = fluid_box(scene, mean_fluid);
        proxy_initial = initial_particles(&proxy, file)?;
        (&proxy, &proxy_initial)
    } else {
        (scene, &initial)
    };
    let work = Calibrate { scene: calibrated_scene, initial: calibrated_initial, wall: calibration };
    let (seconds_per_particle_step, calibration_steps) = with_precision_and_model(precision, calibrated_scene, work);
    Ok(Report {
        initial_fluid: initial.fluid.len(),
        boundary: initial.boundary.len(),
        fluid_capacity: capacity,
        inlet_rate: inlets.iter().map(Inlet::particles_per_second).sum(),
        final_fluid: fluid_at(end, initial.fluid.len(), capacity, inlets) as usize,
        capacity_full: capacity_full(end, initial.fluid.len(), capacity, inlets),
        spacing_m: scene.material.particle_spacing_m,
        support_radius_m: scene.support_radius(),
        speed_bound_m_s: speed_bound,
        mach_bound: speed_bound.map(|v| v / scene.material.sound_speed_m_s),
        bound,
        dt_s: dt,
        limit,
        steps,
        memory_bytes: plan.memory_bytes,
        device_memory_bytes: plan.device_memory_bytes,
        precision,
        threads: rayon::current_num_threads(),
        seconds_per_particle_step,
        calibration_steps,
        particle_steps,
        estimated_wall_s: particle_steps * seconds_per_particle_step,
    })
}
