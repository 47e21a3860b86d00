//! The time loop of a run: steps to the end time, a frame and a checkpoint when one is due,
//! progress, and a clean stop on Ctrl-C, instability or a device fault.

use super::checkpoint::{self, Checkpoint};
use super::folder;
use super::frames::FrameWriter;
use super::progress::Progress;
use super::{io_error, Device, RunError, RunOptions, Summary, Tally};
use crate::cpu::parallel::on_worker;
use crate::output::vtu::{encode, Field};
use crate::output::write_atomically;
use crate::scene::setup::InitialParticles;
use crate::scene::{Scene, SceneError};
use crate::simulation::backend::Backend;
use crate::simulation::model::Model;
use crate::simulation::particles::Particles;
use crate::simulation::variant::WithModel;
use crate::simulation::{RunState, Setup, Simulation, StepError};
use coil_kernels::Real;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// The time loop of a run, for whichever physics variant the scene picks.
pub struct Drive<'a> {
    pub scene: &'a Scene,
    pub initial: &'a InitialParticles,
    pub options: &'a RunOptions,
    pub device: Option<Device>,
    /// Where a resumed run starts.
    pub checkpoint: Option<&'a Checkpoint>,
}

impl WithModel for Drive<'_> {
    type Output = Result<Summary, RunError>;
    fn with<R: Real, M: Model<R>>(self, model: M) -> Self::Output {
        let mut setup = Setup::<R, M>::new(self.scene, self.initial, model);
        let tally = match self.checkpoint {
            None => None,
            Some(c) => {
                c.restore(&mut setup).map_err(|reason| {
                    RunError::Scene(SceneError {
                        file: self.options.out_dir.join(folder::CHECKPOINT).display().to_string(),
                        field: "(file)".into(),
                        reason,
                    })
                })?;
                Some(c.tally.clone())
            }
        };
        let fresh = tally.is_none();
        match self.device {
            None => {
                let mut sim = Simulation::on_cpu(setup, true);
                if fresh {
                    let Ok(()) = sim.sort_and_density();
                }
                // The whole loop on a worker: a step then hands no job to the pool from outside.
                on_worker(|| drive(sim, self.scene, self.initial, self.options, tally))
            }
            #[cfg(feature = "cuda")]
            Some(gpu) => {
                let backend_error = |e: crate::cuda::CudaError| match e {
                    // f32 state takes about two thirds of f64's (docs/benchmark.md's memory table).
                    crate::cuda::CudaError::OutOfMemory { .. } if R::NAME == "f64" => {
                        RunError::Backend(format!("{e}, or run --precision f32 (about two thirds of the memory)"))
                    }
                    e => RunError::Backend(e.to_string()),
                };
                let mut sim = crate::cuda::GpuSimulation::on_gpu(setup, gpu).map_err(backend_error)?;
                if fresh {
                    sim.sort_and_density().map_err(backend_error)?;
                }
                if !self.options.quiet {
                    let bytes = sim.backend.memory_bytes();
                    let per_particle = bytes / sim.particles().capacity().max(1);
                    eprintln!("device memory: {:.1} MiB ({per_particle} B per particle)", bytes as f64 / (1 << 20) as f64);
                }
                drive(sim, self.scene, self.initial, self.options, tally)
            }
            #[cfg(not(feature = "cuda"))]
            Some(d) => match d {},
        }
    }
}

fn drive<R: Real, M: Model<R>, B: Backend<R>>(
    mut sim: Simulation<R, M, B>,
    scene: &Scene,
    initial: &InitialParticles,
    options: &RunOptions,
    resumed: Option<Tally>,
) -> Result<Summary, RunError> {
    let dir = &options.out_dir;
    write_boundary(scene, initial, dir)?;
    let end = scene.simulation.end_time_s;
    let every_s = scene.output.every_s;
    let fresh = resumed.is_none();
    let mut tally = resumed.unwrap_or(Tally { next_frame_time: every_s.unwrap_or(f64::INFINITY), ..Tally::default() });
    let clock = WallClock { started: Instant::now(), earlier_s: tally.wall_s };
    let mut frames = FrameWriter::new(scene, dir, options.preview, &tally);
    let save_checkpoint = |run: &RunState<R, M>, particles: &Particles<R>, tally: &mut Tally| -> Result<(), RunError> {
        tally.wall_s = clock.wall_s();
        let path = dir.join(folder::CHECKPOINT);
        checkpoint::write(dir, run, particles, scene, tally).map_err(|e| io_error("checkpoint", &path, e))
    };
    let series = frames.series_path();
    let summary = |run: &RunState<R, M>, tally: &Tally| clock.summary(run, tally, scene, series.clone());
    if fresh {
        frames.capture(&sim.run, sim.host()).map_err(|i| RunError::Unstable(i, Box::new(summary(&sim.run, &tally))))?;
        frames.write(sim.run.time, &mut tally)?;
        save_checkpoint(&sim.run, &sim.host().particles, &mut tally)?;
    }

    let mut progress = Progress::new(options.quiet);
    let stopped = |stop: StepError<B::Fault>, s: Summary| match stop {
        StepError::Unstable(instability) => RunError::Unstable(instability, Box::new(s)),
        StepError::Backend(e) => RunError::Device(e.to_string(), Box::new(s)),
    };
    let outcome = loop {
        if sim.run.time >= end * (1.0 - 1e-12) {
            break sim.sync();
        }
        let (dt, limit) = sim.next_dt();
        if let Err(stop) = sim.step_with(dt.min(end - sim.run.time), limit) {
            break Err(stop);
        }
        tally.particle_steps += sim.backend.particle_bound() as f64;
        tally.max_compression = tally.max_compression.max(sim.run.diagnostics.max_compression);
        tally.max_speed = tally.max_speed.max(sim.run.diagnostics.max_speed);
        let due = match scene.output.every_steps {
            Some(k) => sim.run.steps.is_multiple_of(k),
            None => sim.run.time >= tally.next_frame_time * (1.0 - 1e-9),
        };
        if due {
            if let Err(stop) = sim.sync() {
                break Err(stop);
            }
            if let Err(instability) = frames.capture(&sim.run, sim.host()) {
                break Err(StepError::Unstable(instability));
            }
            frames.write(sim.run.time, &mut tally)?;
            tally.schedule_past(sim.run.time, every_s);
            save_checkpoint(&sim.run, &sim.host().particles, &mut tally)?;
        }
        progress.report(&sim.run, end, clock.started.elapsed(), tally.particle_steps);
        if sim.settled() && options.stop.is_some_and(|stop| stop.load(Ordering::Relaxed)) {
            progress.finish();
            if let Err(stop) = sim.sync() {
                return Err(stopped(stop, summary(&sim.run, &tally)));
            }
            save_checkpoint(&sim.run, &sim.host().particles, &mut tally)?;
            return Err(RunError::Interrupted(Box::new(summary(&sim.run, &tally))));
        }
    };
    progress.finish();
    outcome.map_err(|stop| stopped(stop, summary(&sim.run, &tally)))?;
    Ok(summary(&sim.run, &tally))
}

/// The wall particles, written once per run for ParaView to show beside the frames.
fn write_boundary(scene: &Scene, initial: &InitialParticles, dir: &std::path::Path) -> Result<(), RunError> {
    let mut bytes = Vec::new();
    let path = dir.join(folder::BOUNDARY);
    encode(&initial.boundary, &[] as &[Field], scene.output.vtu_encoding, &mut bytes);
    write_atomically(&path, &bytes).map_err(|e| io_error("boundary", &path, e))
}

/// Wall time of a run over all the processes that took it up (s).
struct WallClock {
    started: Instant,
    /// What earlier processes spent on a resumed run.
    earlier_s: f64,
}

impl WallClock {
    fn wall_s(&self) -> f64 {
        self.earlier_s + self.started.elapsed().as_secs_f64()
    }

    fn summary<R: Real, M: Model<R>>(
        &self,
        run: &RunState<R, M>,
        tally: &Tally,
        scene: &Scene,
        series: Option<std::path::PathBuf>,
    ) -> Summary {
        let wall = self.wall_s();
        Summary {
            steps: run.steps,
            simulated_s: run.time,
            wall_s: wall,
            particle_steps_per_s: if wall > 0.0 { tally.particle_steps / wall } else { 0.0 },
            fluid_particles: run.fluid_count(),
            boundary_particles: run.boundary_count(),
            max_compression: tally.max_compression,
            max_speed_m_s: tally.max_speed,
            max_mach: tally.max_speed / scene.material.sound_speed_m_s,
            removed: run.removed,
            frames: tally.frame_times.len(),
            capacity_reached: run.capacity_reached_at.map(|t| (t, run.fluid_capacity())),
            implicit_viscosity: run.implicit.map(|settings| run.solves.summary(settings.tolerance, settings.max_iterations)),
            divergence_solve: run
                .pressure_solve
                .map(|settings| run.divergence_solves.summary(settings.divergence_tolerance, settings.max_iterations)),
            density_solve: run
                .pressure_solve
                .map(|settings| run.density_solves.summary(settings.density_tolerance, settings.max_iterations)),
            series,
        }
    }
}
