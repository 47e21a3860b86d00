//! `coil run`: a scene from t = 0 to its end time, on the CPU or a CUDA device, writing frames
//! as it goes.

pub mod checkpoint;
pub mod folder;
pub mod interrupt;
pub mod run_log;
pub mod summary;

use crate::cpu::parallel::on_worker;
use crate::output::frame::Frame;
use crate::output::preview::{own_range, render, speeds, Coloring, View};
use crate::output::vtu::{encode, Field, PvdSeries};
use crate::output::write_atomically;
use crate::run::run_log::{resolved, Resumed, RunLog};
use crate::scene::setup::{initial_particles, InitialParticles};
use crate::scene::{FrameFormat, Precision, Scene, SceneError};
use crate::simulation::backend::Backend as StepBackend;
use crate::simulation::model::{with_precision_and_model, Model, WithModel};
use crate::simulation::particles::HostParticles;
use crate::simulation::{Instability, RunState, Setup, Simulation, StepError};
use checkpoint::Checkpoint;
use coil_kernels::Real;
use folder::{frame_name, series_path};
use indicatif::{ProgressBar, ProgressStyle};
use std::fmt;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
pub use summary::{Summary, Tally};

/// Pixels per panel of `--preview` pictures.
const PREVIEW_SIZE: usize = 480;

/// Where the physics runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    Cpu,
    /// A CUDA device; an error where there is none.
    Cuda,
    /// A CUDA device when this build has the backend and a device is present, else the CPU.
    Auto,
}

#[cfg(feature = "cuda")]
pub type Device = crate::cuda::Gpu;
/// This build has no CUDA backend: no device can exist.
#[cfg(not(feature = "cuda"))]
pub enum Device {}

/// The first CUDA device, or why there is none: no driver, no device, or a build without the
/// backend.
pub fn open_cuda() -> Result<Device, String> {
    #[cfg(feature = "cuda")]
    return crate::cuda::Gpu::open().map_err(|e| e.to_string());
    #[cfg(not(feature = "cuda"))]
    Err("this coil was built without the CUDA backend (rebuild with `cargo build --release --features cuda`)".into())
}

/// Opens the device `backend` asks for; `None` runs on the CPU. Says which it chose.
fn open_device(backend: Backend, quiet: bool) -> Result<Option<Device>, String> {
    let device = match (backend, open_cuda()) {
        (Backend::Cpu, _) => None,
        (_, Ok(device)) => Some(device),
        (Backend::Cuda, Err(e)) => return Err(format!("--backend cuda: {e}")),
        (Backend::Auto, Err(e)) => {
            if !quiet {
                eprintln!("backend: cpu ({e})");
            }
            return Ok(None);
        }
    };
    if !quiet {
        match &device {
            None => eprintln!("backend: cpu"),
            #[cfg(feature = "cuda")]
            Some(gpu) => eprintln!("backend: cuda, {}", gpu.describe()),
            #[cfg(not(feature = "cuda"))]
            Some(d) => match *d {},
        }
    }
    Ok(device)
}

#[derive(Debug, Clone)]
pub struct RunOptions {
    pub backend: Backend,
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
    /// Replace an earlier run's files in `out_dir`; without it such a folder is refused.
    pub overwrite: bool,
    /// Once set (by Ctrl-C through `interrupt::watch`, or by a program driving the run), the run
    /// stops after its step, checkpointed for `coil resume`.
    pub stop: Option<&'static AtomicBool>,
}

#[derive(Debug)]
pub enum RunError {
    /// Bad input (exit code 2).
    Scene(SceneError),
    /// Output could not be written.
    Io(String),
    /// The run went unstable; frames written before are kept.
    Unstable(Instability, Box<Summary>),
    /// The backend asked for is not available here (exit code 2).
    Backend(String),
    /// The device failed during the run; frames written before are kept.
    Device(String, Box<Summary>),
    /// Ctrl-C or SIGTERM stopped the run after a step; frames written before are kept.
    Interrupted(Box<Summary>),
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Scene(e) => e.fmt(f),
            RunError::Io(e) => f.write_str(e),
            RunError::Unstable(i, s) => {
                write!(f, "{i}\nFrames written before it are kept ({}).", s.frames)
            }
            RunError::Backend(e) => f.write_str(e),
            RunError::Device(e, s) => write!(f, "{e}\nFrames written before it are kept ({}).", s.frames),
            RunError::Interrupted(s) => write!(
                f,
                "interrupted at step {} (t = {:.6} s); the {} frames written before are kept",
                s.steps, s.simulated_s, s.frames
            ),
        }
    }
}

/// Runs `scene` (read from `scene_file`) to its end time, on the backend `options` asks for.
pub fn run(scene: &Scene, scene_file: &str, options: &RunOptions) -> Result<Summary, RunError> {
    let device = open_device(options.backend, options.quiet).map_err(RunError::Backend)?;
    run_on(device, scene, scene_file, options)
}

/// [`run`] on a device already opened (the emulated one, in tests), or on the CPU for `None`;
/// `options.backend` is not consulted.
pub fn run_on(device: Option<Device>, scene: &Scene, scene_file: &str, options: &RunOptions) -> Result<Summary, RunError> {
    execute(device, scene, scene_file, options, None)
}

/// A run taken up again from its checkpoint.
struct Resumption {
    checkpoint: Checkpoint,
    /// Where it was resumed before, from its `run.json`.
    earlier: Vec<Resumed>,
}

/// Runs `scene` from t = 0, or from `resumption`'s checkpoint into the folder that holds it.
fn execute(
    device: Option<Device>,
    scene: &Scene,
    scene_file: &str,
    options: &RunOptions,
    resumption: Option<Resumption>,
) -> Result<Summary, RunError> {
    let precision = options.precision.unwrap_or(scene.simulation.precision);
    let mut scene = scene.clone();
    scene.simulation.precision = precision;
    let scene = &scene;
    let initial = initial_particles(scene, scene_file).map_err(RunError::Scene)?;
    if resumption.is_none() {
        clear_earlier_run(scene_file, options)?;
    }
    std::fs::create_dir_all(&options.out_dir).map_err(|e| {
        RunError::Scene(SceneError {
            file: scene_file.into(),
            field: "--out".into(),
            reason: format!("output folder {} cannot be created: {e}", options.out_dir.display()),
        })
    })?;
    let mut resumed = resumption.as_ref().map(|r| r.earlier.clone()).unwrap_or_default();
    if let Some(r) = &resumption {
        resumed.push(Resumed { step: r.checkpoint.steps, time_s: r.checkpoint.time });
    }
    let mut log = RunLog {
        coil_version: env!("CARGO_PKG_VERSION"),
        scene_file,
        overrides: &options.overrides,
        backend: if device.is_some() { "cuda" } else { "cpu" },
        precision,
        threads: rayon::current_num_threads(),
        status: "running",
        diagnosis: None,
        resumed,
        summary: None,
        scene: resolved(scene),
    };
    let log_path = options.out_dir.join(folder::LOG);
    log.write(&options.out_dir).map_err(|e| io_error("run log", &log_path, e))?;
    let checkpoint = resumption.as_ref().map(|r| &r.checkpoint);
    let result = with_precision_and_model(precision, scene, Drive { scene, initial: &initial, options, device, checkpoint });
    (log.status, log.diagnosis, log.summary) = match &result {
        Ok(summary) => ("completed", None, Some(summary.clone())),
        Err(RunError::Unstable(i, summary)) => ("unstable", Some(i.to_string()), Some(Summary::clone(summary))),
        Err(RunError::Device(e, summary)) => ("failed", Some(e.clone()), Some(Summary::clone(summary))),
        Err(e @ RunError::Interrupted(summary)) => ("interrupted", Some(e.to_string()), Some(Summary::clone(summary))),
        Err(e) => ("failed", Some(e.to_string()), None),
    };
    log.write(&options.out_dir).map_err(|e| io_error("run log", &log_path, e))?;
    result
}

/// How `coil resume` goes on.
#[derive(Debug, Clone)]
pub struct ResumeOptions {
    pub backend: Backend,
    pub quiet: bool,
    pub preview: bool,
    /// `--set` overrides of the fields `checkpoint::RESUMABLE` names: a later end time, another
    /// time step, other output.
    pub set: Vec<String>,
    /// As `RunOptions::stop`.
    pub stop: Option<&'static AtomicBool>,
}

/// `coil resume DIR`: takes up the run in `dir` from its checkpoint (the latest frame, or where
/// Ctrl-C stopped it) and runs it to its end time, as `coil run` would have without the stop.
pub fn resume(dir: &Path, options: &ResumeOptions) -> Result<Summary, RunError> {
    let device = open_device(options.backend, options.quiet).map_err(RunError::Backend)?;
    resume_on(device, dir, options)
}

/// [`resume`] on a device already opened, or on the CPU for `None`.
pub fn resume_on(device: Option<Device>, dir: &Path, options: &ResumeOptions) -> Result<Summary, RunError> {
    let log_path = dir.join(folder::LOG);
    let bad = |file: &Path, field: &str, reason: String| {
        RunError::Scene(SceneError { file: file.display().to_string(), field: field.into(), reason })
    };
    let text = std::fs::read_to_string(&log_path).map_err(|e| {
        bad(&log_path, "(file)", format!("cannot be read ({e}): {} is not the output folder of a coil run", dir.display()))
    })?;
    let log: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(&log_path, "(syntax)", e.to_string()))?;
    let mut overrides = Vec::new();
    for given in &options.set {
        let key = given.split_once('=').map_or(given.as_str(), |(key, _)| key.trim());
        let resumable =
            checkpoint::RESUMABLE.iter().any(|f| key == *f || key.strip_prefix(f).is_some_and(|r| r.starts_with('.')));
        if !resumable {
            return Err(bad(
                Path::new("--set"),
                key,
                format!(
                    "cannot change when resuming: the checkpoint holds the state of the scene it was taken from; only {} may",
                    checkpoint::RESUMABLE.join(", ")
                ),
            ));
        }
        overrides.push(crate::scene::overrides::Override::parse(given).map_err(RunError::Scene)?);
    }
    let scene = Scene::load_with(&log_path, &overrides).map_err(RunError::Scene)?;
    let checkpoint_path = dir.join(folder::CHECKPOINT);
    let mut checkpoint = Checkpoint::read(&checkpoint_path).map_err(|e| bad(&checkpoint_path, "(file)", e))?;
    if checkpoint.fingerprint != checkpoint::fingerprint(&scene) {
        return Err(bad(
            &checkpoint_path,
            "(file)",
            format!("was taken from another scene than the one {} logs (edited since the run?)", log_path.display()),
        ));
    }
    if scene.output.every_s != log["scene"]["output"]["every_s"].as_f64() {
        checkpoint.tally.reschedule(scene.output.every_s, checkpoint.time);
    }
    let end = scene.simulation.end_time_s;
    if checkpoint.time >= end * (1.0 - 1e-12) {
        let reason = if options.set.iter().any(|o| o.trim_start().starts_with("simulation.end_time_s")) {
            format!("must be later than the checkpoint's t = {:.6} s, got {end}", checkpoint.time)
        } else {
            format!("the run reached its end time t = {end} s; pass --set simulation.end_time_s=LATER to run it further")
        };
        return Err(bad(&log_path, "simulation.end_time_s", reason));
    }
    let scene_file = log["scene_file"].as_str().unwrap_or_default().to_string();
    let mut all_overrides: Vec<String> =
        log["overrides"].as_array().map(|a| a.iter().filter_map(|o| o.as_str().map(String::from)).collect()).unwrap_or_default();
    all_overrides.extend(options.set.iter().cloned());
    let earlier = serde_json::from_value(log["resumed"].clone()).unwrap_or_default();
    remove_frames_from(dir, checkpoint.tally.frame_times.len())?;
    let run_options = RunOptions {
        backend: options.backend,
        out_dir: dir.to_path_buf(),
        precision: None,
        quiet: options.quiet,
        preview: options.preview,
        overrides: all_overrides,
        overwrite: false,
        stop: options.stop,
    };
    execute(device, &scene, &scene_file, &run_options, Some(Resumption { checkpoint, earlier }))
}

/// Removes the frames numbered `first` and later: written after the checkpoint by a run that
/// was then killed, they will be written again, and must not linger if the resumed run stops
/// before them.
fn remove_frames_from(dir: &Path, first: usize) -> Result<(), RunError> {
    let files = folder::earlier_run_files(dir).map_err(|e| io_error("output folder", dir, e))?;
    for file in files {
        let name = file.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        let number = name.strip_prefix("frame_").and_then(|rest| rest.get(..6)).and_then(|n| n.parse::<usize>().ok());
        if number.is_some_and(|k| k >= first) {
            std::fs::remove_file(&file).map_err(|e| io_error("a frame past the checkpoint", &file, e))?;
        }
    }
    Ok(())
}

/// Refuses an output folder that holds an earlier run, whose frames the new run would
/// overwrite in part and leave stale past its own last frame; with `--overwrite`, removes that
/// run's files first.
fn clear_earlier_run(scene_file: &str, options: &RunOptions) -> Result<(), RunError> {
    let dir = &options.out_dir;
    let earlier = folder::earlier_run_files(dir).map_err(|e| io_error("output folder", dir, e))?;
    if earlier.is_empty() {
        return Ok(());
    }
    if !options.overwrite {
        let frames = earlier
            .iter()
            .filter(|f| f.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("frame_") && n.ends_with(".vtu")))
            .count();
        return Err(RunError::Scene(SceneError {
            file: scene_file.into(),
            field: "--out".into(),
            reason: format!(
                "output folder {} holds an earlier run ({} files, {frames} frames); pass --overwrite to replace it, or --out another folder",
                dir.display(),
                earlier.len()
            ),
        }));
    }
    for file in &earlier {
        std::fs::remove_file(file).map_err(|e| io_error("an earlier run's file", file, e))?;
    }
    Ok(())
}

/// The time loop of a run, for whichever physics variant the scene picks.
struct Drive<'a> {
    scene: &'a Scene,
    initial: &'a InitialParticles,
    options: &'a RunOptions,
    device: Option<Device>,
    /// Where a resumed run starts.
    checkpoint: Option<&'a Checkpoint>,
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

/// The progress bar: simulated time, steps/s, particles, dt and its limiting term, ETA. Where
/// stderr is not a terminal (a log file, CI) a plain line every 10 s replaces it.
struct Progress {
    bar: Option<ProgressBar>,
    last_line: Instant,
    /// Time (s) and steps where this process took the run up, which rates and ETA count from.
    start_time: f64,
    start_steps: u64,
}

impl Progress {
    fn new(quiet: bool, start_time: f64, start_steps: u64) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(1000);
            bar.set_style(
                ProgressStyle::with_template("{bar:30.cyan/blue} {percent:>3}% {msg} ETA {eta}").expect("a valid template"),
            );
            bar
        });
        Self { bar, last_line: Instant::now(), start_time, start_steps }
    }

    fn report<R: Real, M: Model<R>>(&mut self, sim: &RunState<R, M>, end: f64, wall: Duration) {
        let rate = (sim.steps - self.start_steps) as f64 / wall.as_secs_f64().max(1e-9);
        let line = format!(
            "t = {:.4}/{end} s | {rate:.0} steps/s | {} fluid particles{} | dt {:.2e} s ({})",
            sim.time,
            sim.fluid_count(),
            if sim.capacity_reached_at.is_some() { " (capacity full: inlets wait)" } else { "" },
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
                let eta = (end - sim.time) / (sim.time - self.start_time).max(1e-300) * wall.as_secs_f64();
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

fn drive<R: Real, M: Model<R>, B: StepBackend<R>>(
    mut sim: Simulation<R, M, B>,
    scene: &Scene,
    initial: &InitialParticles,
    options: &RunOptions,
    resumed: Option<Tally>,
) -> Result<Summary, RunError> {
    let dir = &options.out_dir;

    let mut bytes = Vec::new();
    let boundary_path = dir.join(folder::BOUNDARY);
    encode(&initial.boundary, &[] as &[Field], scene.output.vtu_encoding, &mut bytes);
    write_atomically(&boundary_path, &bytes).map_err(|e| io_error("boundary", &boundary_path, e))?;

    let end = scene.simulation.end_time_s;
    let every_s = scene.output.every_s;
    let every_steps = scene.output.every_steps;
    let fresh = resumed.is_none();
    let mut tally = resumed.unwrap_or(Tally { next_frame_time: every_s.unwrap_or(f64::INFINITY), ..Tally::default() });
    let earlier_wall_s = tally.wall_s;
    let expected_frames = every_s.map(|e| (end / e).ceil() as usize + 1).unwrap_or(1024);
    let writes_series = scene.output.formats.contains(&FrameFormat::Vtu);
    let series_path = series_path(dir, &scene.name);
    let listed =
        if writes_series { tally.frame_times.iter().enumerate().map(|(k, &t)| (t, frame_name(k))).collect() } else { Vec::new() };
    let mut series = PvdSeries::new(series_path.clone(), expected_frames, listed);
    let mut frame = Frame::default();
    let started = Instant::now();
    let mut write_frame = |run: &RunState<R, M>, host: &HostParticles<R>, tally: &mut Tally| -> Result<(), RunError> {
        frame.capture(run, host);
        let name = frame_name(tally.frame_times.len());
        let path = dir.join(&name);
        for format in &scene.output.formats {
            let (file, bytes) = match format {
                FrameFormat::Vtu => (path.clone(), frame.to_vtu(scene.output.vtu_encoding)),
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
        if writes_series {
            series.push(run.time, &name).map_err(|e| io_error("series", series.path(), e))?;
        }
        tally.frame_times.push(run.time);
        Ok(())
    };
    let save_checkpoint = |run: &RunState<R, M>, host: &HostParticles<R>, tally: &mut Tally| -> Result<(), RunError> {
        tally.wall_s = earlier_wall_s + started.elapsed().as_secs_f64();
        let path = dir.join(folder::CHECKPOINT);
        checkpoint::write(dir, run, &host.particles, scene, tally).map_err(|e| io_error("checkpoint", &path, e))
    };
    if fresh {
        write_frame(&sim.run, sim.host(), &mut tally)?;
        save_checkpoint(&sim.run, sim.host(), &mut tally)?;
    }

    let mut last_report = started;
    let mut progress = Progress::new(options.quiet, sim.run.time, sim.run.steps);
    let summary = |sim: &RunState<R, M>, tally: &Tally| {
        let wall = earlier_wall_s + started.elapsed().as_secs_f64();
        Summary {
            steps: sim.steps,
            simulated_s: sim.time,
            wall_s: wall,
            particle_steps_per_s: if wall > 0.0 { tally.particle_steps / wall } else { 0.0 },
            fluid_particles: sim.fluid_count(),
            boundary_particles: sim.boundary_count(),
            max_compression: tally.max_compression,
            max_speed_m_s: tally.max_speed,
            max_mach: tally.max_speed / scene.material.sound_speed_m_s,
            removed: sim.removed,
            frames: tally.frame_times.len(),
            capacity_reached: sim.capacity_reached_at.map(|t| (t, sim.fluid_capacity())),
            series: writes_series.then(|| series_path.clone()),
        }
    };
    let stopped = |stop: StepError<B::Fault>, s: Summary| match stop {
        StepError::Unstable(instability) => RunError::Unstable(instability, Box::new(s)),
        StepError::Backend(e) => RunError::Device(e.to_string(), Box::new(s)),
    };
    while sim.run.time < end * (1.0 - 1e-12) {
        let (dt, limit) = sim.next_dt();
        let dt = dt.min(end - sim.run.time);
        if let Err(stop) = sim.step_with(dt, limit) {
            progress.finish();
            return Err(stopped(stop, summary(&sim.run, &tally)));
        }
        tally.particle_steps += sim.backend.particle_bound() as f64;
        let run = &sim.run;
        tally.max_compression = tally.max_compression.max(run.diagnostics.max_compression);
        tally.max_speed = tally.max_speed.max(run.diagnostics.max_speed);
        let due = match every_steps {
            Some(k) => run.steps.is_multiple_of(k),
            None => run.time >= tally.next_frame_time * (1.0 - 1e-9),
        };
        if due {
            if let Err(stop) = sim.sync() {
                progress.finish();
                return Err(stopped(stop, summary(&sim.run, &tally)));
            }
            write_frame(&sim.run, sim.host(), &mut tally)?;
            tally.schedule_past(sim.run.time, every_s);
            save_checkpoint(&sim.run, sim.host(), &mut tally)?;
        }
        if !options.quiet && last_report.elapsed() >= Duration::from_millis(200) {
            last_report = Instant::now();
            progress.report(&sim.run, end, started.elapsed());
        }
        if sim.settled() && options.stop.is_some_and(|stop| stop.load(Ordering::Relaxed)) {
            progress.finish();
            if let Err(stop) = sim.sync() {
                return Err(stopped(stop, summary(&sim.run, &tally)));
            }
            save_checkpoint(&sim.run, sim.host(), &mut tally)?;
            return Err(RunError::Interrupted(Box::new(summary(&sim.run, &tally))));
        }
    }
    progress.finish();
    if let Err(stop) = sim.sync() {
        return Err(stopped(stop, summary(&sim.run, &tally)));
    }
    Ok(summary(&sim.run, &tally))
}
