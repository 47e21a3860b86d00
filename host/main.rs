//! The `coil` command line.

mod cli;

use clap::Parser;
use cli::args::{
    BenchBackendArg, CameraArg, Cli, ColorArg, Command, Execution, MeshFormatArg, PrecisionArg, RenderColorArg, ViewArg,
};
use cli::commands::{bench_command, finish_run, list_scenes, preview, print_axis, tradeoff_command};
use cli::pov::{pov_command, PovOptions};
use cli::render::{render_command, RenderColor, RenderOptions};
use cli::surface::{surface_command, SurfaceOptions};
use coil::bench::{cuda_available, table_row, BenchBackend, BenchOptions};
use coil::check::check;
use coil::output::preview::{Coloring, View};
use coil::output::render::Camera;
use coil::output::surface::MeshFormat;
use coil::run::{resume, run, ResumeOptions, RunOptions};
use coil::scene::overrides::Override;
use coil::scene::Scene;
use coil::validation::jet_axis::offsets_in_run;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Threads a core may be given at most: past a few a core, threads only wait for each other,
/// and thousands would take the machine's memory and time before the first step.
const THREADS_PER_CORE: usize = 4;

/// Sizes rayon's pool; `None` keeps one thread per core.
fn set_threads(threads: Option<usize>) -> Result<(), String> {
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    let most = THREADS_PER_CORE * cores;
    match threads {
        None => Ok(()),
        Some(t) if !(1..=most).contains(&t) => Err(format!(
            "--threads: must be from 1 to {most} ({THREADS_PER_CORE} for each of this machine's {cores} cores), got {t}"
        )),
        Some(t) => rayon::ThreadPoolBuilder::new().num_threads(t).build_global().map_err(|e| format!("--threads: {e}")),
    }
}

/// A `--range MIN,MAX` of colours, if given.
fn colour_range(range: Option<&[f64]>) -> Result<Option<(f64, f64)>, String> {
    match range {
        None => Ok(None),
        Some(&[min, max]) if min < max => Ok(Some((min, max))),
        Some(r) => Err(format!("--range: expected MIN,MAX with MIN < MAX, got {r:?}")),
    }
}

/// The overrides of `--variant NAME` (the variant's list in the scene file) followed by `set`.
fn with_variant(path: &Path, variant: Option<&str>, set: Vec<String>) -> Result<Vec<String>, String> {
    let Some(name) = variant else { return Ok(set) };
    let scene = Scene::load(path).map_err(|e| e.to_string())?;
    let Some(found) = scene.variants.iter().find(|v| v.name == name) else {
        let names: Vec<&str> = scene.variants.iter().map(|v| v.name.as_str()).collect();
        let known = if names.is_empty() { "it has none".to_string() } else { format!("it has {}", names.join(", ")) };
        return Err(format!("{}: --variant {name}: the scene has no such variant; {known}", path.display()));
    };
    Ok(found.set.iter().cloned().chain(set).collect())
}

/// Reads a scene and applies its `--set` overrides, validating the result.
fn load_scene(path: &Path, set: &[String]) -> Result<Scene, String> {
    let overrides = set.iter().map(|o| Override::parse(o)).collect::<Result<Vec<_>, _>>().map_err(|e| e.to_string())?;
    Scene::load_with(path, &overrides).map_err(|e| e.to_string())
}

/// Every command's bad input ends here: one `error:` line and exit code 2.
fn main() -> ExitCode {
    coil::run::interrupt::end_on_closed_pipe();
    match command(Cli::parse().command) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn command(command: Command) -> Result<ExitCode, String> {
    match command {
        Command::Scenes { dir } => list_scenes(&dir),
        Command::Axis { dir } => {
            let (axis, offsets) = offsets_in_run(&dir)?;
            print_axis(&dir, &axis, &offsets);
            Ok(ExitCode::SUCCESS)
        }
        Command::Surface { path, cube_size, support_radius, iso, format, threads, quiet } => {
            set_threads(threads)?;
            let formats: &'static [MeshFormat] =
                match (format.contains(&MeshFormatArg::Ply), format.contains(&MeshFormatArg::Obj)) {
                    (true, true) => &[MeshFormat::Ply, MeshFormat::Obj],
                    (false, true) => &[MeshFormat::Obj],
                    _ => &[MeshFormat::Ply],
                };
            let options = SurfaceOptions { cube_size, support_radius, iso_threshold: iso, formats, quiet };
            surface_command(&path, &options).map(|()| ExitCode::SUCCESS)
        }
        Command::Render { path, views, color, range, size, delay, threads, quiet } => {
            set_threads(threads)?;
            let cameras = views
                .iter()
                .map(|v| match v {
                    CameraArg::Front => Camera::Front,
                    CameraArg::Side => Camera::Side,
                    CameraArg::Top => Camera::Top,
                    CameraArg::Oblique => Camera::Oblique,
                })
                .collect();
            let color = match color {
                RenderColorArg::Auto => RenderColor::Auto,
                RenderColorArg::Viscosity => RenderColor::Viscosity,
                RenderColorArg::Speed => RenderColor::Speed,
            };
            let range = colour_range(range.as_deref())?;
            let options = RenderOptions { cameras, color, range, size, movie_delay_cs: delay, quiet };
            render_command(&path, &options).map(|()| ExitCode::SUCCESS)
        }
        Command::Pov { path, render, size, color, threads } => {
            set_threads(threads)?;
            let size = match size.as_slice() {
                &[w, h] if (16..=8192).contains(&w) && (16..=8192).contains(&h) => (w, h),
                s => return Err(format!("--size: expected WIDTH,HEIGHT, each 16 to 8192 pixels, got {s:?}")),
            };
            let by_viscosity = match color {
                RenderColorArg::Auto => None,
                RenderColorArg::Viscosity => Some(true),
                RenderColorArg::Speed => Some(false),
            };
            pov_command(&path, &PovOptions { render: render.then_some(size), by_viscosity }).map(|()| ExitCode::SUCCESS)
        }
        Command::Tradeoff { quick, repeats, out } => tradeoff_command(quick, repeats as usize, &out).map(|()| ExitCode::SUCCESS),
        Command::Validate { quick, only, out } => {
            Ok(if coil::validation::suite::run(quick, &only, &out)? { ExitCode::SUCCESS } else { ExitCode::from(1) })
        }
        Command::Bench { sizes, precision, backend, steps, cpu_large_steps, warmup, profile_steps, threads, out } => {
            set_threads(threads)?;
            let sizes = sizes
                .iter()
                .map(|s| {
                    table_row(s).ok_or_else(|| format!("--sizes: `{s}` is not a size of Table I (1K,4K,16K,64K,128K,256K,1M)"))
                })
                .collect::<Result<Vec<_>, _>>()?;
            if steps == 0 || cpu_large_steps == 0 {
                return Err("--steps and --cpu-large-steps: must be at least 1".to_string());
            }
            let backends = match backend {
                BenchBackendArg::Cpu => vec![BenchBackend::Cpu],
                BenchBackendArg::Cuda => vec![BenchBackend::Cuda],
                BenchBackendArg::Both => vec![BenchBackend::Cpu, BenchBackend::Cuda],
                BenchBackendArg::Auto => match cuda_available() {
                    Ok(()) => vec![BenchBackend::Cpu, BenchBackend::Cuda],
                    Err(why) => {
                        eprintln!("backend: cpu only ({why})");
                        vec![BenchBackend::Cpu]
                    }
                },
            };
            let options = BenchOptions {
                sizes,
                precisions: precision.iter().map(|p| p.precision()).collect(),
                backends,
                steps,
                cpu_large_steps,
                warmup,
                profile_steps,
            };
            bench_command(&options, &out).map(|()| ExitCode::SUCCESS)
        }
        Command::Check { scene, set, variant, precision, threads, calibrate_s } => {
            let file = scene.display().to_string();
            set_threads(threads)?;
            let parsed = load_scene(&scene, &with_variant(&scene, variant.as_deref(), set)?)?;
            let calibration = std::time::Duration::from_secs_f64(calibrate_s.clamp(0.0, 600.0));
            let report = check(&parsed, &file, precision.map(PrecisionArg::precision), calibration).map_err(|e| e.to_string())?;
            println!("{file}: valid\n{report}");
            Ok(ExitCode::SUCCESS)
        }
        Command::Preview { frame, view, color, range, size, output } => {
            let view = match view {
                ViewArg::Side => View::Side,
                ViewArg::Top => View::Top,
                ViewArg::Both => View::Both,
            };
            let coloring = match color {
                ColorArg::Viscosity => Coloring::Viscosity,
                ColorArg::Speed => Coloring::Speed,
            };
            let range = colour_range(range.as_deref())?;
            println!("{}", preview(&frame, view, coloring, range, size, output)?.display());
            Ok(ExitCode::SUCCESS)
        }
        Command::Run {
            scene,
            set,
            variant,
            out,
            precision,
            execution: Execution { backend, threads, quiet, preview },
            overwrite,
        } => {
            let file = scene.display().to_string();
            set_threads(threads)?;
            let set = with_variant(&scene, variant.as_deref(), set)?;
            let parsed = load_scene(&scene, &set)?;
            let folder = match &variant {
                Some(name) => format!("{}-{name}", parsed.name),
                None => parsed.name.clone(),
            };
            let options = RunOptions {
                backend: backend.backend(),
                out_dir: out.unwrap_or_else(|| PathBuf::from("out").join(folder)),
                precision: precision.map(PrecisionArg::precision),
                quiet,
                preview,
                overrides: set,
                overwrite,
                stop: Some(coil::run::interrupt::watch()),
            };
            Ok(finish_run(run(&parsed, &file, &options), &options.out_dir))
        }
        Command::Resume { dir, set, execution: Execution { backend, threads, quiet, preview } } => {
            set_threads(threads)?;
            let options =
                ResumeOptions { backend: backend.backend(), quiet, preview, set, stop: Some(coil::run::interrupt::watch()) };
            Ok(finish_run(resume(&dir, &options), &dir))
        }
    }
}
