//! The `coil` command line.

use clap::{Parser, Subcommand, ValueEnum};
use coil::run::{run, RunError, RunOptions};
use coil::scene::{Precision, Scene};
use std::path::PathBuf;
use std::process::ExitCode;

/// SPH simulation of viscous and shear-thinning liquids that buckle, coil and fold
/// (Andrade et al., "SPH Fluids for Viscous Jet Buckling", SIBGRAPI 2014).
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene on the CPU and write frames (.vtu + .pvd for ParaView).
    Run {
        /// Scene file (TOML), e.g. scenes/round_jet.toml.
        scene: PathBuf,
        /// Output folder [default: out/<scene name>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Floating-point precision of the physics [default: the scene's].
        #[arg(long, value_enum)]
        precision: Option<PrecisionArg>,
        /// Worker threads [default: all cores].
        #[arg(long)]
        threads: Option<usize>,
        /// Print only the summary.
        #[arg(long)]
        quiet: bool,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum PrecisionArg {
    F32,
    F64,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Run { scene, out, precision, threads, quiet } => {
            if let Some(t) = threads {
                if t == 0 {
                    eprintln!("error: --threads: must be at least 1");
                    return ExitCode::from(2);
                }
                if let Err(e) = rayon::ThreadPoolBuilder::new().num_threads(t).build_global() {
                    eprintln!("error: --threads: {e}");
                    return ExitCode::from(2);
                }
            }
            let file = scene.display().to_string();
            let parsed = match Scene::load(&scene) {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("error: {e}");
                    return ExitCode::from(2);
                }
            };
            let options = RunOptions {
                out_dir: out.unwrap_or_else(|| PathBuf::from("out").join(&parsed.name)),
                precision: precision.map(|p| match p {
                    PrecisionArg::F32 => Precision::F32,
                    PrecisionArg::F64 => Precision::F64,
                }),
                quiet,
            };
            match run(&parsed, &file, &options) {
                Ok(summary) => {
                    println!("{summary}");
                    println!("frames in {} (open {}.pvd in ParaView)", options.out_dir.display(), parsed.name);
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(match e {
                        RunError::Scene(_) => 2,
                        RunError::Io(_) => 1,
                        RunError::Unstable(..) => 3,
                    })
                }
            }
        }
    }
}
