//! `coil run`: a scene on the CPU from t = 0 to its end time, writing frames as it goes.

use crate::frame::Frame;
use crate::model::{with_model, Model, WithModel};
use crate::output::vtu::{encode, Field, Series};
use crate::output::write_atomically;
use crate::preview::{own_range, render, speeds, Coloring, View};
use crate::run_log::{resolved, RunLog};
use crate::scene::{FrameFormat, Precision, Scene, SceneError};
use crate::setup::{initial_particles, InitialParticles};
use crate::simulation::{Instability, Simulation};
use coil_kernels::Real;
use indicatif::{ProgressBar, ProgressStyle};
use std::fmt;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Pixels per panel of `--preview` pictures.
const PREVIEW_SIZE: usize = 480;

#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Folder for frames; created if missing.
    pub out_dir: PathBuf,
    /// Overrides the scene's precision.
    pub precision: Option<Precision>,
    /// No progress lines.
    pub quiet: bool,
    /// Also write each frame as a PNG (`coil preview`'s picture, both views).
    pub preview: bool,
    /// The `--set` overrides the scene went through, for the run log.
    pub overrides: Vec<String>,
}

/// What a run did, printed at its end.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Summary {
    pub steps: u64,
    pub simulated_s: f64,
    pub wall_s: f64,
    pub particle_steps_per_s: f64,
    pub fluid_particles: usize,
    pub boundary_particles: usize,
    pub max_density_error: f64,
    pub max_speed_m_s: f64,
    /// Largest speed over c.
    pub max_mach: f64,
    pub removed: u64,
    pub frames: usize,
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "steps                  {}", self.steps)?;
        writeln!(f, "simulated time         {:.6} s", self.simulated_s)?;
        writeln!(f, "wall time              {:.2} s", self.wall_s)?;
        writeln!(f, "particle-steps/s       {:.3e}", self.particle_steps_per_s)?;
        writeln!(f, "particles              {} fluid, {} boundary", self.fluid_particles, self.boundary_particles)?;
        writeln!(f, "max |rho-rho0|/rho0    {:.3e}", self.max_density_error)?;
        writeln!(f, "max speed              {:.4} m/s (Mach {:.3})", self.max_speed_m_s, self.max_mach)?;
        writeln!(f, "removed (left domain)  {}", self.removed)?;
        write!(f, "frames                 {}", self.frames)
    }
}

#[derive(Debug)]
pub enum RunError {
    /// Bad input (exit code 2).
    Scene(SceneError),
    /// Output could not be written.
    Io(String),
    /// The run went unstable; frames written before are kept.
    Unstable(Instability, Summary),
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Scene(e) => e.fmt(f),
            RunError::Io(e) => f.write_str(e),
            RunError::Unstable(i, s) => {
                write!(f, "{i}\nFrames written before it are kept ({}).", s.frames)
            }
        }
    }
}

/// Runs `scene` (read from `scene_file`) to its end time.
pub fn run(scene: &Scene, scene_file: &str, options: &RunOptions) -> Result<Summary, RunError> {
    let initial = initial_particles(scene, scene_file).map_err(RunError::Scene)?;
    std::fs::create_dir_all(&options.out_dir).map_err(|e| {
        RunError::Scene(SceneError {
            file: scene_file.into(),
            field: "--out".into(),
            reason: format!("output folder {} cannot be created: {e}", options.out_dir.display()),
        })
    })?;
    let precision = options.precision.unwrap_or(scene.simulation.precision);
    let mut log = RunLog {
        coil_version: env!("CARGO_PKG_VERSION"),
        scene_file,
        overrides: &options.overrides,
        backend: "cpu",
        precision,
        threads: rayon::current_num_threads(),
        status: "running",
        diagnosis: None,
        summary: None,
        scene: resolved(scene),
    };
    log.scene.simulation.precision = precision;
    let log_path = options.out_dir.join("run.json");
    log.write(&options.out_dir).map_err(|e| io_error("run log", &log_path, e))?;
    let result = match precision {
        Precision::F32 => with_model::<f32, _>(scene, Drive { scene, initial: &initial, options }),
        Precision::F64 => with_model::<f64, _>(scene, Drive { scene, initial: &initial, options }),
    };
    (log.status, log.diagnosis, log.summary) = match &result {
        Ok(summary) => ("completed", None, Some(summary.clone())),
        Err(RunError::Unstable(i, summary)) => ("unstable", Some(i.to_string()), Some(summary.clone())),
        Err(e) => ("failed", Some(e.to_string()), None),
    };
    log.write(&options.out_dir).map_err(|e| io_error("run log", &log_path, e))?;
    result
}

/// The time loop of a run, for whichever physics variant the scene picks.
struct Drive<'a> {
    scene: &'a Scene,
    initial: &'a InitialParticles,
    options: &'a RunOptions,
}

impl WithModel for Drive<'_> {
    type Output = Result<Summary, RunError>;
    fn with<R: Real, M: Model<R>>(self, model: M) -> Self::Output {
        drive(self.scene, self.initial, model, self.options)
    }
}

/// The progress bar: simulated time, steps/s, particles, dt and its limiting term, ETA. Where
/// stderr is not a terminal (a log file, CI) a plain line every 10 s replaces it.
struct Progress {
    bar: Option<ProgressBar>,
    last_line: Instant,
}

impl Progress {
    fn new(quiet: bool) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(1000);
            bar.set_style(
                ProgressStyle::with_template("{bar:30.cyan/blue} {percent:>3}% {msg} ETA {eta}").expect("a valid template"),
            );
            bar
        });
        Self { bar, last_line: Instant::now() }
    }

    fn report<R: Real, M: Model<R>>(&mut self, sim: &Simulation<R, M>, end: f64, wall: Duration) {
        let rate = sim.steps as f64 / wall.as_secs_f64().max(1e-9);
        let line = format!(
            "t = {:.4}/{end} s | {rate:.0} steps/s | {} fluid particles | dt {:.2e} s ({})",
            sim.time,
            sim.fluid_count(),
            sim.last_dt,
            sim.last_limit
        );
        match &self.bar {
            Some(bar) => {
                bar.set_position((1000.0 * sim.time / end) as u64);
                bar.set_message(line);
            }
            None if self.last_line.elapsed() >= Duration::from_secs(10) => {
                self.last_line = Instant::now();
                let eta = (end - sim.time) / sim.time.max(1e-300) * wall.as_secs_f64();
                eprintln!("{line} | ETA {eta:.0} s");
            }
            None => {}
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

fn io_error(what: &str, path: &std::path::Path, e: std::io::Error) -> RunError {
    RunError::Io(format!("cannot write {what} {}: {e}", path.display()))
}

fn drive<R: Real, M: Model<R>>(
    scene: &Scene,
    initial: &InitialParticles,
    model: M,
    options: &RunOptions,
) -> Result<Summary, RunError> {
    let mut sim = Simulation::<R, M>::new(scene, initial, model);
    let dir = &options.out_dir;

    let mut bytes = Vec::new();
    let boundary_path = dir.join("boundary.vtu");
    encode(&initial.boundary, &[] as &[Field], &mut bytes);
    write_atomically(&boundary_path, &bytes).map_err(|e| io_error("boundary", &boundary_path, e))?;

    let end = scene.simulation.end_time_s;
    let every_s = scene.output.every_s;
    let every_steps = scene.output.every_steps;
    let expected_frames = every_s.map(|e| (end / e).ceil() as usize + 1).unwrap_or(1024);
    let mut series = Series::new(dir.join(format!("{}.pvd", scene.name)), expected_frames);
    let mut frame = Frame::default();
    let mut frames = 0usize;
    let mut write_frame = |sim: &Simulation<R, M>, frames: &mut usize| -> Result<(), RunError> {
        frame.capture(sim);
        let name = format!("frame_{:06}.vtu", *frames);
        let path = dir.join(&name);
        for format in &scene.output.formats {
            let (file, bytes) = match format {
                FrameFormat::Vtu => (path.clone(), frame.to_vtu()),
                FrameFormat::Ply => (path.with_extension("ply"), frame.to_ply()),
                FrameFormat::Xyz => (path.with_extension("xyz"), frame.to_xyz()),
            };
            write_atomically(&file, bytes).map_err(|e| io_error("frame", &file, e))?;
        }
        if options.preview {
            let v = &scene.material.viscosity;
            // The paper's colouring, nu_inf to nu0; a Newtonian fluid has one colour, so speed.
            let image = if v.nu_inf() < v.nu0_m2_s {
                render(&frame.position, &frame.viscosity, (v.nu_inf(), v.nu0_m2_s), View::Both, PREVIEW_SIZE)
            } else {
                let speed = speeds(&frame.velocity);
                render(&frame.position, &speed, own_range(Coloring::Speed, &speed), View::Both, PREVIEW_SIZE)
            };
            let png = path.with_extension("png");
            image.save(&png).map_err(|e| io_error("preview", &png, e))?;
        }
        if scene.output.formats.contains(&FrameFormat::Vtu) {
            series.push(sim.time, &name).map_err(|e| io_error("series", series.path(), e))?;
        }
        *frames += 1;
        Ok(())
    };
    write_frame(&sim, &mut frames)?;

    let started = Instant::now();
    let mut last_report = started;
    let mut progress = Progress::new(options.quiet);
    let mut particle_steps = 0f64;
    let mut max_density_error = 0f64;
    let mut max_speed = 0f64;
    let mut next_frame_time = every_s.unwrap_or(f64::INFINITY);
    let summary = |sim: &Simulation<R, M>, frames: usize, particle_steps: f64, max_density_error: f64, max_speed: f64| {
        let wall = started.elapsed().as_secs_f64();
        Summary {
            steps: sim.steps,
            simulated_s: sim.time,
            wall_s: wall,
            particle_steps_per_s: if wall > 0.0 { particle_steps / wall } else { 0.0 },
            fluid_particles: sim.fluid_count(),
            boundary_particles: sim.boundary_count(),
            max_density_error,
            max_speed_m_s: max_speed,
            max_mach: max_speed / scene.material.sound_speed_m_s,
            removed: sim.removed,
            frames,
        }
    };
    while sim.time < end * (1.0 - 1e-12) {
        let (dt, limit) = sim.next_dt();
        let dt = dt.min(end - sim.time);
        if let Err(instability) = sim.step_with(dt, limit) {
            progress.finish();
            let s = summary(&sim, frames, particle_steps, max_density_error, max_speed);
            return Err(RunError::Unstable(instability, s));
        }
        particle_steps += sim.particles.len() as f64;
        max_density_error = max_density_error.max(sim.diagnostics.max_density_error);
        max_speed = max_speed.max(sim.diagnostics.max_speed);
        let due = match every_steps {
            Some(k) => sim.steps % k == 0,
            None => sim.time >= next_frame_time * (1.0 - 1e-9),
        };
        if due {
            write_frame(&sim, &mut frames)?;
            while next_frame_time <= sim.time * (1.0 + 1e-9) {
                next_frame_time += every_s.unwrap_or(f64::INFINITY);
            }
        }
        if !options.quiet && last_report.elapsed() >= Duration::from_millis(200) {
            last_report = Instant::now();
            progress.report(&sim, end, started.elapsed());
        }
    }
    progress.finish();
    Ok(summary(&sim, frames, particle_steps, max_density_error, max_speed))
}
