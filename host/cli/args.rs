//! The command line's words: commands, their flags and what each means.

use clap::{Args, Parser, Subcommand, ValueEnum};
use coil::run::Backend;
use coil::scene::Precision;
use std::path::PathBuf;

/// SPH simulation of viscous and shear-thinning liquids that buckle, coil and fold
/// (Andrade et al., "SPH Fluids for Viscous Jet Buckling", SIBGRAPI 2014).
#[derive(Parser)]
#[command(version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// How `run` and `resume` execute a run.
#[derive(Args)]
pub struct Execution {
    /// Where the physics runs: cpu; cuda (an NVIDIA GPU; needs a build with
    /// `--features cuda`); or auto (a CUDA device when this build has the backend and one is
    /// present, else the CPU). Resumed on the backend it started on, a run writes the frames of
    /// one never stopped bit for bit; on another, the same physics in another rounding.
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: BackendArg,
    /// Worker threads [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print only the summary.
    #[arg(long)]
    pub quiet: bool,
    /// Also write each frame as a PNG next to it (as `coil preview` draws it, coloured by
    /// viscosity from nu_inf to nu0, or by speed for a Newtonian fluid).
    #[arg(long)]
    pub preview: bool,
}

#[derive(Subcommand)]
pub enum Command {
    /// Run a scene on the CPU or a CUDA GPU and write frames (.vtu + .pvd for ParaView).
    Run {
        /// Scene file (TOML), e.g. scenes/round_jet.toml.
        scene: PathBuf,
        /// Override a scene field, validated like the file: KEY is the dotted path as the file
        /// spells it, e.g. --set material.viscosity.cross_k_s=10 --set inlet[0].speed_m_s=0.5.
        /// Repeatable; applied in order.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Apply the scene's variant NAME first (its list of fields, as `coil scenes` prints
        /// it), then any --set; the output folder defaults to out/<scene name>-<NAME>.
        #[arg(long, value_name = "NAME")]
        variant: Option<String>,
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
    /// Reconstruct the free surface of a run's frames (marching cubes over an SPH density field,
    /// splashsurf) and write each mesh beside its frame as frame_NNNN.surface.ply (binary, with
    /// normals and the fluid's viscosity in m^2/s and speed in m/s at each vertex) or .obj.
    Surface {
        /// A run's output folder (every frame of its series) or one .vtu frame.
        path: PathBuf,
        /// Marching-cubes edge, in particle spacings.
        #[arg(long, default_value_t = 0.5)]
        cube_size: f64,
        /// Support radius of the density field's kernel, in the run's h.
        #[arg(long, default_value_t = 1.0)]
        support_radius: f64,
        /// The surface is where the density field reaches this fraction of rho0.
        #[arg(long, default_value_t = 0.6)]
        iso: f64,
        /// Mesh formats (comma-separated).
        #[arg(long, value_enum, value_delimiter = ',', default_value = "ply")]
        format: Vec<MeshFormatArg>,
        /// Worker threads [default: all cores].
        #[arg(long)]
        threads: Option<usize>,
        /// Print only the result.
        #[arg(long)]
        quiet: bool,
    },
    /// Draw the free surface of a run's frames from fixed cameras (front, side, top and oblique),
    /// shaded and coloured by viscosity (m^2/s) or speed (m/s), with the time, the plate, a
    /// scale bar and a colour bar: frame_NNNN.render.png beside each frame and, for a run's
    /// folder, the movie render.gif, and render.mp4 where ffmpeg is installed.
    Render {
        /// A run's output folder (every frame of its series) or one .vtu frame.
        path: PathBuf,
        /// Cameras, left to right (comma-separated).
        #[arg(long, value_enum, value_delimiter = ',', default_value = "front,side,top,oblique")]
        views: Vec<CameraArg>,
        /// What the colours show [default: viscosity for a Cross fluid, speed otherwise].
        #[arg(long, value_enum, default_value = "auto")]
        color: RenderColorArg,
        /// Colour range MIN,MAX [default: nu_inf to nu0, or 0 to the run's top speed].
        #[arg(long, value_delimiter = ',', value_name = "MIN,MAX")]
        range: Option<Vec<f64>>,
        /// Pixels per panel side.
        #[arg(long, default_value_t = 400)]
        size: usize,
        /// Hundredths of a second each frame shows in the movie.
        #[arg(long, default_value_t = 8)]
        delay: u16,
        /// Worker threads [default: all cores].
        #[arg(long)]
        threads: Option<usize>,
        /// Print only the result.
        #[arg(long)]
        quiet: bool,
    },
    /// Write a POV-Ray scene beside each frame as the paper renders its figures: the fluid one
    /// blob, a component of radius h per particle coloured by viscosity (or speed), the plate, a
    /// camera fixed across the run; with --render, render each with povray where installed.
    Pov {
        /// A run's output folder (every frame of its series) or one .vtu frame.
        path: PathBuf,
        /// Render each scene with povray to frame_NNNNNN.pov.png.
        #[arg(long)]
        render: bool,
        /// Picture size WIDTH,HEIGHT for --render.
        #[arg(long, value_delimiter = ',', value_name = "WIDTH,HEIGHT", default_value = "800,600")]
        size: Vec<u32>,
        /// What the colours show [default: viscosity for a Cross fluid, speed otherwise].
        #[arg(long, value_enum, default_value = "auto")]
        color: RenderColorArg,
        /// Worker threads [default: all cores].
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Validate a scene and say what it will cost: particle counts, h, the Eq. (10) bound and
    /// its limiting term, memory, and the wall time estimated from a short calibration run.
    Check {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Override a scene field, as for `run`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Apply the scene's variant NAME first, as for `run`.
        #[arg(long, value_name = "NAME")]
        variant: Option<String>,
        /// Floating-point precision [default: the scene's].
        #[arg(long, value_enum)]
        precision: Option<PrecisionArg>,
        /// Worker threads [default: all cores].
        #[arg(long)]
        threads: Option<usize>,
        /// Seconds of calibration run (more than 0, at most 3600).
        #[arg(long, default_value_t = 2.0, value_parser = calibration_seconds)]
        calibrate_s: f64,
    },
    /// Reproduce the paper's Table I: the dam break at 1K to 1M fluid particles, median ms per
    /// step on the CPU and a CUDA GPU in f32 and f64, beside the paper's figures. Writes
    /// bench.md, bench.csv, kernels.csv (GPU kernel times from CUDA events) and the plot as
    /// bench.png, bench.svg and bench.plot.csv.
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
    /// spreading, a viscous thread falling freely against the slender-thread solution, and jet
    /// buckling from high and low nozzles), print each error next to its
    /// tolerance, and plot simulated against reference profiles (PNG, SVG, CSV). Exits 1 when a
    /// binding case fails; the paper's operator below the binding resolution and on the Cross
    /// cases is shown for comparison.
    Validate {
        /// Coarser resolutions and no jets: about half an hour on 2 cores; the full set takes hours.
        #[arg(long)]
        quick: bool,
        /// Run only these groups of cases (comma-separated): poiseuille, cross, tank,
        /// taylor-green, torus, huppert, thread, jet (not with --quick).
        #[arg(long, value_delimiter = ',')]
        only: Vec<coil::validation::suite::Group>,
        /// Output folder for plots and validate.md.
        #[arg(long, default_value = "out/validate")]
        out: PathBuf,
    },
    /// Measure what each speed-for-accuracy knob buys on the two Poiseuille cases (resolution,
    /// operator, dt safety factor, the velocity the viscous terms read, the viscosity solver,
    /// sound speed, precision, walls, density kernel): error against the reference and the
    /// median wall time of each trial's repeats; writes tradeoff.md, tradeoff.csv and the plot of error against time, the
    /// Pareto front drawn (tradeoff.png, .svg, .plot.csv).
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
    /// jet (below 0.1 D), with its direction; then what the rope's foot did: straight, folding
    /// (back and forth through the axis), coiling (round it one way, with its turns and turns a
    /// second) or irregular. For a run of one round, still, downward inlet, written as .vtu
    /// frames.
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
pub enum CameraArg {
    Front,
    Side,
    Top,
    Oblique,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RenderColorArg {
    Auto,
    Viscosity,
    Speed,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MeshFormatArg {
    Ply,
    Obj,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BackendArg {
    Auto,
    Cpu,
    Cuda,
}

impl BackendArg {
    pub fn backend(self) -> Backend {
        match self {
            BackendArg::Auto => Backend::Auto,
            BackendArg::Cpu => Backend::Cpu,
            BackendArg::Cuda => Backend::Cuda,
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchBackendArg {
    Auto,
    Cpu,
    Cuda,
    Both,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum ViewArg {
    Side,
    Top,
    Both,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum ColorArg {
    Viscosity,
    Speed,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PrecisionArg {
    F32,
    F64,
}

impl PrecisionArg {
    pub fn precision(self) -> Precision {
        match self {
            PrecisionArg::F32 => Precision::F32,
            PrecisionArg::F64 => Precision::F64,
        }
    }
}

/// A calibration time (s): a positive, finite number of at most an hour.
fn calibration_seconds(text: &str) -> Result<f64, String> {
    let s: f64 = text.trim().parse().map_err(|e| format!("{e}"))?;
    if s > 0.0 && s <= 3600.0 {
        Ok(s)
    } else {
        Err(format!("must be more than 0 and at most 3600 seconds, got {text}"))
    }
}
