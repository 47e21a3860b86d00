//! The `coil` command line.

use clap::{Args, Parser, Subcommand, ValueEnum};
use coil::bench::report::{chart, csv, kernels_csv, markdown};
use coil::bench::{bench, cuda_available, precision_name, table_row, BenchBackend, BenchOptions};
use coil::output::preview::{frame_path, render_frame, Coloring, View};
use coil::output::vtu_read::read_frame;
use coil::output::write_atomically;
use coil::run::{resume, run, Backend, ResumeOptions, RunError, RunOptions, Summary};
use coil::scene::check::check;
use coil::scene::overrides::Override;
use coil::scene::{Precision, Scene, ViscousVelocity};
use coil::validation::jet_axis::{offsets_in_run, AxisSample, JetAxis};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// SPH simulation of viscous and shear-thinning liquids that buckle, coil and fold
/// (Andrade et al., "SPH Fluids for Viscous Jet Buckling", SIBGRAPI 2014).
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// How `run` and `resume` execute a run.
#[derive(Args)]
struct Execution {
    /// Where the physics runs: cpu; cuda (an NVIDIA GPU; needs a build with
    /// `--features cuda`); or auto (a CUDA device when this build has the backend and one is
    /// present, else the CPU). Resumed on the backend it started on, a run writes the frames of
    /// one never stopped bit for bit; on another, the same physics in another rounding.
    #[arg(long, value_enum, default_value = "auto")]
    backend: BackendArg,
    /// Worker threads [default: all cores].
    #[arg(long)]
    threads: Option<usize>,
    /// Print only the summary.
    #[arg(long)]
    quiet: bool,
    /// Also write each frame as a PNG next to it (as `coil preview` draws it, coloured by
    /// viscosity from nu_inf to nu0, or by speed for a Newtonian fluid).
    #[arg(long)]
    preview: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene on the CPU or a CUDA GPU and write frames (.vtu + .pvd for ParaView).
    Run {
        /// Scene file (TOML), e.g. scenes/round_jet.toml.
        scene: PathBuf,
        /// Override a scene field, validated like the file: KEY is the dotted path as the file
        /// spells it, e.g. --set material.viscosity.cross_k_s=10 --set inlet[0].speed_m_s=0.5.
        /// Repeatable; applied in order.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Output folder [default: out/<scene name>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Floating-point precision of the physics [default: the scene's].
        #[arg(long, value_enum)]
        precision: Option<PrecisionArg>,
        #[command(flatten)]
        execution: Execution,
        /// Replace an earlier run in the output folder (its log, checkpoint, series and frames; nothing
        /// else there). Without it such a folder is refused, so that no run is lost by mistake.
        #[arg(long)]
        overwrite: bool,
    },
    /// Continue a run that stopped (Ctrl-C, a kill, a crash, a lost machine, an instability)
    /// from its checkpoint, the latest frame or where Ctrl-C stopped it, into the same folder:
    /// the frames come out as the run would have written them without the stop.
    Resume {
        /// The run's output folder (it holds run.json and checkpoint.bin).
        dir: PathBuf,
        /// Change a field the checkpoint does not fix, as `run --set` does: a later
        /// simulation.end_time_s, simulation.time_step.* (to get past an instability from the
        /// last good frame), output.*.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        #[command(flatten)]
        execution: Execution,
    },
    /// Render a frame to a PNG: orthographic, coloured by viscosity (as the paper's figures) or
    /// speed, with a colour bar.
    Preview {
        /// A frame (.vtu) or an output folder (its last frame).
        frame: PathBuf,
        /// Camera: side (along -z), top (along -y) or both.
        #[arg(long, value_enum, default_value = "both")]
        view: ViewArg,
        /// What the colours show.
        #[arg(long, value_enum, default_value = "viscosity")]
        color: ColorArg,
        /// Colour range MIN,MAX [default: the frame's own range; 0 to the top speed].
        #[arg(long, value_delimiter = ',', value_name = "MIN,MAX")]
        range: Option<Vec<f64>>,
        /// Pixels per panel side.
        #[arg(long, default_value_t = 600)]
        size: usize,
        /// PNG to write [default: the frame's name with .png].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Validate a scene and say what it will cost: particle counts, h, the Eq. (10) bound and
    /// its limiting term, memory, and the wall time estimated from a short calibration run.
    Check {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Override a scene field, as for `run`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Floating-point precision [default: the scene's].
        #[arg(long, value_enum)]
        precision: Option<PrecisionArg>,
        /// Worker threads [default: all cores].
        #[arg(long)]
        threads: Option<usize>,
        /// Seconds of calibration run.
        #[arg(long, default_value_t = 2.0)]
        calibrate_s: f64,
    },
    /// Reproduce the paper's Table I: the dam break at 1K to 1M fluid particles, median ms per
    /// step on the CPU and a CUDA GPU in f32 and f64, beside the paper's figures. Writes
    /// bench.md, bench.csv, kernels.csv (GPU kernel times from CUDA events) and bench.png.
    Bench {
        /// Table I sizes to run, comma-separated: 1K,4K,16K,64K,128K,256K,1M.
        #[arg(long, value_delimiter = ',', default_value = "1K,4K,16K,64K,128K,256K,1M")]
        sizes: Vec<String>,
        /// Precisions, comma-separated.
        #[arg(long, value_enum, value_delimiter = ',', default_value = "f32,f64")]
        precision: Vec<PrecisionArg>,
        /// cpu, cuda, both, or auto (both when a CUDA device is present, else the CPU).
        #[arg(long, value_enum, default_value = "auto")]
        backend: BenchBackendArg,
        /// Timed steps per measurement.
        #[arg(long, default_value_t = 100)]
        steps: usize,
        /// Timed CPU steps at sizes above 64K (labelled in the report).
        #[arg(long, default_value_t = 20)]
        cpu_large_steps: usize,
        /// Untimed steps before timing.
        #[arg(long, default_value_t = 20)]
        warmup: usize,
        /// GPU steps timed kernel by kernel with CUDA events, after the timed steps.
        #[arg(long, default_value_t = 20)]
        profile_steps: usize,
        /// Worker threads of the CPU backend [default: all cores].
        #[arg(long)]
        threads: Option<usize>,
        /// Output folder.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
    },
    /// Compare coil with published references (start-up Poiseuille flow against Morris et al.
    /// 1997 with each viscosity operator, steady Poiseuille flow of Cross fluids, a hydrostatic
    /// tank, the Taylor-Green vortex, the spreading torus of Fig. 3, Huppert's viscous
    /// spreading, and jet buckling from high and low nozzles), print each error next to its
    /// tolerance, and write PNG plots of simulated against reference profiles. Exits 1 when a
    /// binding case fails; the paper's operator below the binding resolution and on the Cross
    /// cases is shown for comparison.
    Validate {
        /// Coarser resolutions and no jets: about 5 minutes on 2 cores, against about 40 minutes.
        #[arg(long)]
        quick: bool,
        /// Run only these groups of cases (comma-separated): poiseuille, cross, tank,
        /// taylor-green, torus, huppert, jet (not with --quick).
        #[arg(long, value_delimiter = ',')]
        only: Vec<coil::validation::suite::Group>,
        /// Output folder for plots and validate.md.
        #[arg(long, default_value = "out/validate")]
        out: PathBuf,
    },
    /// Measure what each speed-for-accuracy knob buys on the two Poiseuille cases (resolution,
    /// operator, dt safety factor, the velocity the viscous terms read, sound speed, precision,
    /// walls, density kernel): error against the reference and the median wall time of each
    /// trial's repeats; writes tradeoff.md, tradeoff.csv and tradeoff.png (error against time,
    /// the Pareto front drawn).
    Tradeoff {
        /// A few coarse trials (about 13 s a repeat) instead of the full sweep (about 5 minutes a
        /// repeat, on 2 cores).
        #[arg(long)]
        quick: bool,
        /// Runs of each trial; the table gives the median wall time and the range.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
        repeats: u32,
        /// Output folder.
        #[arg(long, default_value = "out/tradeoff")]
        out: PathBuf,
    },
    /// Measure in a run's frames how far a jet swings: the offset over D, frame by frame, of its
    /// axis just above the plate (the centroid of the downward flux between D/2 and 3D/2 above
    /// it) from the nozzle's axis, as `coil validate` judges buckling (above 0.5 D) and a straight
    /// jet (below 0.1 D). For a run of one round, still, downward inlet, written as .vtu frames.
    Axis {
        /// The run's output folder (it holds run.json and the .pvd series).
        dir: PathBuf,
    },
    /// List the shipped scenes, one line each, with what each reproduces.
    Scenes {
        /// Folder of scene files.
        #[arg(default_value = "scenes")]
        dir: PathBuf,
    },
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendArg {
    Auto,
    Cpu,
    Cuda,
}

impl BackendArg {
    fn backend(self) -> Backend {
        match self {
            BackendArg::Auto => Backend::Auto,
            BackendArg::Cpu => Backend::Cpu,
            BackendArg::Cuda => Backend::Cuda,
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BenchBackendArg {
    Auto,
    Cpu,
    Cuda,
    Both,
}

#[derive(Clone, Copy, ValueEnum)]
enum ViewArg {
    Side,
    Top,
    Both,
}

#[derive(Clone, Copy, ValueEnum)]
enum ColorArg {
    Viscosity,
    Speed,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum PrecisionArg {
    F32,
    F64,
}

impl PrecisionArg {
    fn precision(self) -> Precision {
        match self {
            PrecisionArg::F32 => Precision::F32,
            PrecisionArg::F64 => Precision::F64,
        }
    }
}

/// Sizes rayon's pool; `None` keeps one thread per core.
fn set_threads(threads: Option<usize>) -> Result<(), String> {
    match threads {
        None => Ok(()),
        Some(0) => Err("--threads: must be at least 1".into()),
        Some(t) => rayon::ThreadPoolBuilder::new().num_threads(t).build_global().map_err(|e| format!("--threads: {e}")),
    }
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
        Command::Check { scene, set, precision, threads, calibrate_s } => {
            let file = scene.display().to_string();
            set_threads(threads)?;
            let parsed = load_scene(&scene, &set)?;
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
            let range = match range.as_deref() {
                None => None,
                Some(&[min, max]) if min < max => Some((min, max)),
                Some(r) => return Err(format!("--range: expected MIN,MAX with MIN < MAX, got {r:?}")),
            };
            println!("{}", preview(&frame, view, coloring, range, size, output)?.display());
            Ok(ExitCode::SUCCESS)
        }
        Command::Run { scene, set, out, precision, execution: Execution { backend, threads, quiet, preview }, overwrite } => {
            let file = scene.display().to_string();
            set_threads(threads)?;
            let parsed = load_scene(&scene, &set)?;
            let options = RunOptions {
                backend: backend.backend(),
                out_dir: out.unwrap_or_else(|| PathBuf::from("out").join(&parsed.name)),
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

/// Prints the axis offset at each frame's time and the largest; frames where nothing fell
/// through the slab read "-".
fn print_axis(dir: &Path, axis: &JetAxis, offsets: &[AxisSample]) {
    let d = axis.diameter_m;
    println!(
        "{}: jet axis offset over D = {d} m, from the nozzle axis x = {} m, z = {} m, of the downward flux {} to {} m above the plate at y = {} m",
        dir.display(),
        axis.nozzle_xz_m[0],
        axis.nozzle_xz_m[1],
        0.5 * d,
        1.5 * d,
        axis.plate_y_m
    );
    println!("t (s)      offset / D");
    for &AxisSample { time_s: t, offset_over_d } in offsets {
        match offset_over_d {
            Some(o) => println!("{t:<10.6} {o:.6}"),
            None => println!("{t:<10.6} -"),
        }
    }
    let largest = offsets.iter().filter_map(|s| s.offset_over_d.map(|o| (s.time_s, o))).max_by(|a, b| a.1.total_cmp(&b.1));
    match largest {
        Some((t, o)) => println!("largest: {o:.4} D at t = {t:.6} s (straight below 0.1 D, buckled above 0.5 D)"),
        None => println!("largest: none; no frame has fluid falling through the slab"),
    }
}

/// Prints how a run or a resumed run ended, and its exit code: 0 done, 2 bad input, 1 output
/// or device failure, 3 unstable, 130 interrupted.
fn finish_run(result: Result<Summary, RunError>, out_dir: &Path) -> ExitCode {
    match result {
        Ok(summary) => {
            println!("{summary}");
            match &summary.series {
                Some(series) => println!("frames in {} (open {} in ParaView)", out_dir.display(), series.display()),
                None => println!("frames in {}", out_dir.display()),
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            match &e {
                RunError::Interrupted(_) => eprintln!("`coil resume {}` continues it", out_dir.display()),
                RunError::Unstable(i, _) => {
                    eprintln!(
                        "`coil resume {} --set simulation.time_step.fixed_s={:.3e}` continues it from its last frame with a smaller dt",
                        out_dir.display(),
                        (0.5 * i.dt_s).min(i.stability_bound_s)
                    );
                    if i.viscous_velocity == ViscousVelocity::FullStep {
                        eprintln!(
                            "`coil resume {} --set simulation.time_step.viscous_velocity=half_step` continues it at the same dt, the viscous terms reading the half-step velocity, which leap-frog keeps stable to twice the damping rate (docs/tradeoff.md)",
                            out_dir.display()
                        );
                    }
                }
                _ => {}
            }
            ExitCode::from(match e {
                RunError::Scene(_) | RunError::Backend(_) => 2,
                RunError::Io(_) | RunError::Device(..) => 1,
                RunError::Unstable(..) => 3,
                RunError::Interrupted(_) => 130,
            })
        }
    }
}

/// `coil bench`: measures, prints the Markdown table and writes the report files.
fn bench_command(options: &BenchOptions, out: &Path) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("--out: {} cannot be created: {e}", out.display()))?;
    let report = bench(options, |m| {
        eprintln!(
            "{:>4} {} {:<4}: {} fluid + {} boundary particles, median {:.3} ms per step over {} steps",
            m.size.label,
            precision_name(m.precision),
            m.backend.name(),
            m.fluid,
            m.boundary,
            m.median_ms,
            m.steps
        )
    })?;
    let text = markdown(&report, options);
    let write = |name: &str, bytes: &[u8]| {
        let path = out.join(name);
        write_atomically(&path, bytes).map_err(|e| format!("{}: cannot be written: {e}", path.display()))
    };
    write("bench.md", text.as_bytes())?;
    write("bench.csv", csv(&report).as_bytes())?;
    write("kernels.csv", kernels_csv(&report).as_bytes())?;
    write("bench.png", &chart(&report).render(900, 640).to_png())?;
    println!("{text}");
    println!("report in {}", out.display());
    Ok(())
}

/// `coil tradeoff`: runs the sweeps and writes the table and the plot, of the trials measured
/// before a failure where one ended the sweep.
fn tradeoff_command(quick: bool, repeats: usize, out: &Path) -> Result<(), String> {
    use coil::validation::tradeoff::{chart, csv, markdown, run, trials};
    std::fs::create_dir_all(out).map_err(|e| format!("--out: {} cannot be created: {e}", out.display()))?;
    let sweep = run(trials(quick), repeats);
    let measured = sweep.measured;
    let write = |name: &str, bytes: &[u8]| {
        let path = out.join(name);
        write_atomically(&path, bytes).map_err(|e| format!("{}: cannot be written: {e}", path.display()))
    };
    write("tradeoff.md", markdown(&measured).as_bytes())?;
    write("tradeoff.csv", csv(&measured).as_bytes())?;
    write("tradeoff.png", &chart(&measured).render(900, 640).to_png())?;
    match sweep.failure {
        None => {
            println!("table and plot in {}", out.display());
            Ok(())
        }
        Some(e) => {
            Err(format!("the sweep ended at {e}; the {} trials measured before it are in {}", measured.len(), out.display()))
        }
    }
}

fn list_scenes(dir: &Path) -> Result<ExitCode, String> {
    let entries = std::fs::read_dir(dir).map_err(|e| {
        format!("{}: cannot be read: {e} (run from the repository root, or give the scenes folder)", dir.display())
    })?;
    let mut paths: Vec<PathBuf> =
        entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|x| x == "toml")).collect();
    paths.sort();
    let mut status = ExitCode::SUCCESS;
    for path in paths {
        match Scene::load(&path) {
            Ok(scene) => {
                println!("{:<32} {}", path.display(), scene.description);
                for v in &scene.variants {
                    let sets: String = v.set.iter().map(|s| format!(" --set {s}")).collect();
                    println!("  {:<30} {}\n  {:<30} coil run {}{sets}", v.name, v.description, "", path.display());
                }
            }
            Err(e) => {
                eprintln!("error: {e}");
                status = ExitCode::from(2);
            }
        }
    }
    Ok(status)
}

/// `coil preview`: renders the frame `path` names and returns the PNG written.
fn preview(
    path: &Path,
    view: View,
    coloring: Coloring,
    range: Option<(f64, f64)>,
    size: usize,
    output: Option<PathBuf>,
) -> Result<PathBuf, String> {
    if !(16..=8192).contains(&size) {
        return Err(format!("--size: must be 16 to 8192 pixels, got {size}"));
    }
    let file = frame_path(path)?;
    let frame = read_frame(&file)?;
    let image = render_frame(&frame, view, coloring, range, size).map_err(|e| format!("{}: {e}", file.display()))?;
    let png = output.unwrap_or_else(|| file.with_extension("png"));
    image.save(&png).map_err(|e| format!("{}: cannot be written: {e}", png.display()))?;
    Ok(png)
}
