//! `coil run`: a scene from t = 0 to its end time, on the CPU or a CUDA device, writing frames
//! as it goes.

pub mod checkpoint;
mod checkpoint_arrays;
mod checkpoint_bytes;
pub mod fields;
pub mod folder;
mod frames;
pub mod interrupt;
pub mod progress;
pub mod run_log;
pub mod summary;
mod time_loop;

use crate::run::run_log::{resolved, BackendName, Resumed, RunLog, Status};
use crate::scene::setup::initial_particles;
use crate::scene::{Precision, Scene, SceneError};
use crate::simulation::variant::with_precision_and_model;
use crate::simulation::Instability;
use checkpoint::Checkpoint;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
pub use summary::{Summary, Tally};
use time_loop::Drive;

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
    /// The lock on its output folder, held from before the folder was read.
    _lock: std::fs::File,
}

/// Takes output folder `dir` for this run, or refuses it (naming `field` of `file`) where
/// another run holds it.
fn lock_folder(dir: &Path, file: &str, field: &str) -> Result<std::fs::File, RunError> {
    let error = |reason: String| RunError::Scene(SceneError { file: file.into(), field: field.into(), reason });
    folder::lock(dir)
        .map_err(|e| error(format!("output folder {} cannot be locked: {e}", dir.display())))?
        .ok_or_else(|| error(format!("output folder {} is in use by another coil run", dir.display())))
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
    scene.check_precision(precision, scene_file).map_err(RunError::Scene)?;
    let mut scene = scene.clone();
    scene.simulation.precision = precision;
    let scene = &scene;
    let initial = initial_particles(scene, scene_file).map_err(RunError::Scene)?;
    let folder_error = |reason: String| RunError::Scene(SceneError { file: scene_file.into(), field: "--out".into(), reason });
    let dir = &options.out_dir;
    std::fs::create_dir_all(dir).map_err(|e| folder_error(format!("output folder {} cannot be created: {e}", dir.display())))?;
    // A resumed run holds the lock already, taken before it read the folder.
    let _lock = match resumption {
        Some(_) => None,
        None => Some(lock_folder(dir, scene_file, "--out")?),
    };
    if resumption.is_none() {
        clear_earlier_run(scene_file, options)?;
    }
    let mut resumed = resumption.as_ref().map(|r| r.earlier.clone()).unwrap_or_default();
    if let Some(r) = &resumption {
        resumed.push(Resumed { step: r.checkpoint.steps, time_s: r.checkpoint.time });
    }
    let mut log = RunLog {
        coil_version: env!("CARGO_PKG_VERSION").into(),
        scene_file: scene_file.into(),
        overrides: options.overrides.clone(),
        backend: if device.is_some() { BackendName::Cuda } else { BackendName::Cpu },
        precision,
        threads: rayon::current_num_threads(),
        status: Status::Running,
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
        Ok(summary) => (Status::Completed, None, Some(summary.clone())),
        Err(RunError::Unstable(i, summary)) => (Status::Unstable, Some(i.to_string()), Some(Summary::clone(summary))),
        Err(RunError::Device(e, summary)) => (Status::Failed, Some(e.clone()), Some(Summary::clone(summary))),
        Err(e @ RunError::Interrupted(summary)) => (Status::Interrupted, Some(e.to_string()), Some(Summary::clone(summary))),
        Err(e) => (Status::Failed, Some(e.to_string()), None),
    };
    match (log.write(&options.out_dir), result) {
        (Ok(()), result) => result,
        (Err(e), Ok(_)) => Err(io_error("run log", &log_path, e)),
        // The run's own failure comes first; a full disk typically fails both.
        (Err(e), Err(failure)) => {
            Err(RunError::Io(format!("{failure}\nThe run log {} could not record it either: {e}", log_path.display())))
        }
    }
}

/// How `coil resume` goes on.
#[derive(Debug, Clone)]
pub struct ResumeOptions {
    pub backend: Backend,
    pub quiet: bool,
    pub preview: bool,
    /// `--set` overrides of the fields `fields::RESUMABLE` names: a later end time, another
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
    if !log_path.is_file() {
        return Err(bad(&log_path, "(file)", format!("is missing: {} is not the output folder of a coil run", dir.display())));
    }
    let lock = lock_folder(dir, &dir.display().to_string(), "(folder)")?;
    let log = RunLog::read(&log_path).map_err(RunError::Scene)?;
    let mut overrides = Vec::new();
    for given in &options.set {
        let key = given.split_once('=').map_or(given.as_str(), |(key, _)| key.trim());
        let resumable = fields::RESUMABLE.iter().any(|f| key == *f || key.strip_prefix(f).is_some_and(|r| r.starts_with('.')));
        if !resumable {
            return Err(bad(
                Path::new("--set"),
                key,
                format!(
                    "cannot change when resuming: the checkpoint holds the state of the scene it was taken from; only {} may",
                    fields::RESUMABLE.join(", ")
                ),
            ));
        }
        overrides.push(crate::scene::overrides::Override::parse(given).map_err(RunError::Scene)?);
    }
    let scene = Scene::from_log(&log.scene, &log_path, &overrides).map_err(RunError::Scene)?;
    let checkpoint_path = dir.join(folder::CHECKPOINT);
    // Anything at the path is read, and refused there if it is not a regular file.
    if !checkpoint_path.exists() {
        return Err(bad(
            &checkpoint_path,
            "(file)",
            format!(
                "is missing: the run stopped before it saved its first frame, so there is nothing to resume; start it again with `{}`",
                rerun(&log, dir)
            ),
        ));
    }
    let mut checkpoint = Checkpoint::read(&checkpoint_path).map_err(|e| bad(&checkpoint_path, "(file)", e))?;
    if checkpoint.fingerprint != fields::fingerprint(&scene) {
        return Err(bad(
            &checkpoint_path,
            "(file)",
            format!("was taken from another scene than the one {} logs (edited since the run?)", log_path.display()),
        ));
    }
    if scene.output.every_s != log.scene.output.every_s {
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
    verify_frames(dir, &checkpoint.tally.frame_files, &log)?;
    let mut all_overrides = log.overrides;
    all_overrides.extend(options.set.iter().cloned());
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
    execute(device, &scene, &log.scene_file, &run_options, Some(Resumption { checkpoint, earlier: log.resumed, _lock: lock }))
}

/// Refuses to resume where a frame the run keeps is no longer as it wrote it (deleted, cut
/// short, replaced): the checkpoint cannot write an earlier frame again.
fn verify_frames(dir: &Path, files: &[summary::WrittenFile], log: &RunLog) -> Result<(), RunError> {
    for file in files {
        let path = dir.join(&file.name);
        let problem = match crate::regular_file::read(&path, file.bytes) {
            Err(e) => format!("cannot be read: {e}"),
            Ok(bytes) if bytes.len() as u64 != file.bytes => {
                format!("holds {} bytes where the run wrote {}", bytes.len(), file.bytes)
            }
            Ok(bytes) if crate::fnv1a::fnv1a(&bytes) != file.digest => "was changed since the run wrote it".to_string(),
            Ok(_) => continue,
        };
        return Err(RunError::Scene(SceneError {
            file: path.display().to_string(),
            field: "(file)".into(),
            reason: format!(
                "{problem}; the checkpoint cannot write an earlier frame again, so start the run over with `{}`",
                rerun(log, dir)
            ),
        }));
    }
    Ok(())
}

/// The command that runs the run `log` logs again from the start, into `dir`.
fn rerun(log: &RunLog, dir: &Path) -> String {
    let sets: String = log.overrides.iter().map(|o| format!(" --set {o}")).collect();
    format!("coil run {}{sets} --out {} --overwrite", log.scene_file, dir.display())
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

fn io_error(what: &str, path: &std::path::Path, e: std::io::Error) -> RunError {
    RunError::Io(format!("cannot write {what} {}: {e}", path.display()))
}
