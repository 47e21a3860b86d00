//! What a run did: the summary printed at its end and logged, and the running figures of its
//! time loop that checkpoints carry.

use std::fmt;
use std::path::PathBuf;

/// The usual aims of weakly compressible SPH (Monaghan 1994): the flow at most a tenth of the
/// sound speed, so that the density strays about 1 % (it goes as Mach squared).
pub const MACH_AIM: f64 = 0.1;
pub const COMPRESSION_AIM: f64 = 0.01;

/// What a run did, printed at its end.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Summary {
    pub steps: u64,
    pub simulated_s: f64,
    pub wall_s: f64,
    pub particle_steps_per_s: f64,
    pub fluid_particles: usize,
    pub boundary_particles: usize,
    /// Largest compression (rho - rho0) / rho0 over the fluid and the steps checked.
    pub max_compression: f64,
    pub max_speed_m_s: f64,
    /// Largest speed over c.
    pub max_mach: f64,
    pub removed: u64,
    pub frames: usize,
    /// When (s) the fluid capacity (`simulation.max_fluid_particles`) stopped the inlets, and
    /// that capacity.
    pub capacity_reached: Option<(f64, usize)>,
    /// The implicit viscosity solves of this process's steps, where viscosity is solved
    /// implicitly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub implicit_viscosity: Option<Solves>,
    /// The divergence-free pressure's divergence and density solves of this process's steps,
    /// where pressure is solved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub divergence_solve: Option<Solves>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density_solve: Option<Solves>,
    /// The `.pvd` series that ParaView opens, where the run writes `.vtu` frames.
    #[serde(skip)]
    pub series: Option<PathBuf>,
}

/// The solves of one kind of a run, and their settings.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Solves {
    pub mean_iterations: f64,
    pub largest_iterations: u32,
    /// Steps whose solve stopped above its tolerance.
    pub unconverged_steps: u64,
    pub tolerance: f64,
    pub max_iterations: u32,
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "steps                  {}", self.steps)?;
        writeln!(f, "simulated time         {:.6} s", self.simulated_s)?;
        writeln!(f, "wall time              {:.2} s", self.wall_s)?;
        writeln!(f, "particle-steps/s       {:.3e}", self.particle_steps_per_s)?;
        writeln!(f, "particles              {} fluid, {} boundary", self.fluid_particles, self.boundary_particles)?;
        let within = |value: f64, aim: f64| if value <= aim { "within" } else { "above" };
        if self.density_solve.is_some() {
            writeln!(
                f,
                "max compression        {:.3e} ((rho-rho0)/rho0) of a single particle; the density solve holds the fluid's mean to its tolerance",
                self.max_compression
            )?;
            writeln!(f, "max speed              {:.4} m/s (pressure solved: no sound speed)", self.max_speed_m_s)?;
        } else {
            writeln!(
                f,
                "max compression        {:.3e} ((rho-rho0)/rho0): {} the usual aim of {COMPRESSION_AIM} for weakly compressible SPH",
                self.max_compression,
                within(self.max_compression, COMPRESSION_AIM)
            )?;
            writeln!(
                f,
                "max speed              {:.4} m/s (Mach {:.3}: {} the usual aim of {MACH_AIM}; a higher sound speed lowers both, at a shorter dt)",
                self.max_speed_m_s,
                self.max_mach,
                within(self.max_mach, MACH_AIM)
            )?;
        }
        writeln!(f, "removed (left domain)  {}", self.removed)?;
        let solves = [
            ("implicit viscosity", &self.implicit_viscosity),
            ("divergence solve", &self.divergence_solve),
            ("density solve", &self.density_solve),
        ];
        for (name, s) in solves {
            if let Some(s) = s {
                writeln!(
                    f,
                    "{name:<22} {:.1} iterations a step on average, {} at most (tolerance {:.0e}, at most {}); {} step(s) unconverged",
                    s.mean_iterations, s.largest_iterations, s.tolerance, s.max_iterations, s.unconverged_steps
                )?;
            }
        }
        write!(f, "frames                 {}", self.frames)?;
        if let Some((t, capacity)) = self.capacity_reached {
            write!(
                f,
                "\ninlets stopped         at t = {t:.4} s: the fluid capacity of {capacity} particles (simulation.max_fluid_particles) was full"
            )?;
        }
        Ok(())
    }
}

/// The running figures of a run's time loop that its summary and frame schedule need; kept in
/// checkpoints, so that a resumed run carries them on.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Tally {
    /// Simulated time (s) of each frame written, in order.
    pub frame_times: Vec<f64>,
    /// Every frame file written, in order, as it was written: what a resumed run checks the
    /// frames it keeps against.
    pub frame_files: Vec<WrittenFile>,
    /// When the next frame is due (s), with `output.every_s`.
    pub next_frame_time: f64,
    /// Particles moved, summed over steps.
    pub particle_steps: f64,
    pub max_compression: f64,
    /// Largest fluid speed over all steps (m/s).
    pub max_speed: f64,
    /// Wall time the run has taken (s): before this process, then up to the last checkpoint.
    pub wall_s: f64,
}

/// A file as a run wrote it into its output folder.
#[derive(Debug, Clone, PartialEq)]
pub struct WrittenFile {
    /// Its name in the output folder.
    pub name: String,
    pub bytes: u64,
    /// FNV-1a of its bytes.
    pub digest: u64,
}

impl WrittenFile {
    pub fn of(name: String, bytes: &[u8]) -> Self {
        Self { name, bytes: bytes.len() as u64, digest: crate::fnv1a::fnv1a(bytes) }
    }
}

impl Tally {
    /// Puts the next frame `every_s` after the last one written, or at the first such time after
    /// `now` (s), for a run resumed with another `output.every_s`: the schedule it was stopped on
    /// would write its next frame at the old interval.
    pub fn reschedule(&mut self, every_s: Option<f64>, now: f64) {
        let Some(every) = every_s else {
            self.next_frame_time = f64::INFINITY;
            return;
        };
        self.next_frame_time = self.frame_times.last().copied().unwrap_or(0.0) + every;
        self.schedule_past(now, every_s);
    }

    /// Moves the next frame past `now` (s) in steps of `every_s`.
    pub(crate) fn schedule_past(&mut self, now: f64, every_s: Option<f64>) {
        while self.next_frame_time <= now * (1.0 + 1e-9) {
            self.next_frame_time += every_s.unwrap_or(f64::INFINITY);
        }
    }
}
