//! What the commands that do more than call the library do: report, write and print.

use coil::bench::report::{chart, csv, kernels_csv, markdown};
use coil::bench::{bench, precision_name, BenchOptions};
use coil::output::preview::{frame_path, render_frame, Coloring, View};
use coil::output::vtu_read::{read_frame, read_run_frame};
use coil::output::write_atomically;
use coil::run::folder::LOG;
use coil::run::{RunError, Summary};
use coil::scene::{Scene, ViscousVelocity};
use coil::validation::jet_axis::{AxisSample, JetAxis};
use coil::validation::rope_motion::{rope_motion, Pattern, RopeMotion, OFF_AXIS, STRAIGHT_BELOW};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Prints the axis offset and its direction at each frame's time, the largest offset, and what
/// the rope's foot did; frames where nothing fell through the slab read "-".
pub fn print_axis(dir: &Path, axis: &JetAxis, offsets: &[AxisSample]) {
    let d = axis.diameter_m;
    println!(
        "{}: jet axis offset over D = {d} m, from the nozzle axis x = {} m, z = {} m, of the downward flux {} to {} m above the plate at y = {} m; direction from +z towards +x (counter-clockwise seen from above)",
        dir.display(),
        axis.nozzle_xz_m[0],
        axis.nozzle_xz_m[1],
        0.5 * d,
        1.5 * d,
        axis.plate_y_m
    );
    println!("t (s)      offset / D  direction (deg)");
    for sample in offsets {
        match (sample.offset_over_d(), sample.angle_rad()) {
            (Some(o), Some(a)) => println!("{:<10.6} {o:<11.6} {:>6.1}", sample.time_s, a.to_degrees()),
            _ => println!("{:<10.6} -", sample.time_s),
        }
    }
    let Some(motion) = rope_motion(offsets) else {
        println!("largest: none; no frame has fluid falling through the slab");
        return;
    };
    println!(
        "largest: {:.4} D at t = {:.6} s (straight below {STRAIGHT_BELOW} D, buckled above 0.5 D)",
        motion.largest_offset_over_d, motion.largest_at_s
    );
    println!("{}", describe_motion(&motion));
}

/// The pattern line of `coil axis`.
fn describe_motion(m: &RopeMotion) -> String {
    let Some(from) = m.off_axis_from_s else {
        return format!("pattern: {}: never {OFF_AXIS} D off the axis", m.pattern);
    };
    let reading = format!(
        "from t = {from:.3} s, {:.3} s: net {:+.2} turns ({:.2} either way; + is counter-clockwise seen from above), roundness {:.2}, {} crossings of the axis",
        m.duration_s, m.turns, m.turns_either_way, m.roundness, m.folds
    );
    match (m.pattern, m.frequency_hz()) {
        (Pattern::Coiling, Some(f)) => {
            format!("pattern: coiling, {:.2} turns, {f:.2} turns a second ({:.3} s a turn); {reading}", m.turns.abs(), 1.0 / f)
        }
        (Pattern::Folding, Some(f)) => format!("pattern: folding, {f:.2} folds a second ({:.3} s a fold); {reading}", 1.0 / f),
        (p, _) => format!("pattern: {p}; {reading}"),
    }
}

/// Whether the run in `dir` is one `coil axis` reads: one round, still jet falling onto a plate.
fn is_round_jet(dir: &Path) -> bool {
    let log = dir.join(coil::run::folder::LOG);
    Scene::load_with(&log, &[]).is_ok_and(|scene| JetAxis::of(&scene, "run.json").is_ok())
}

/// Prints how a run or a resumed run ended, and its exit code: 0 done, 2 bad input, 1 output
/// or device failure, 3 unstable, 130 interrupted.
pub fn finish_run(result: Result<Summary, RunError>, out_dir: &Path) -> ExitCode {
    match result {
        Ok(summary) => {
            println!("{summary}");
            match &summary.series {
                Some(series) => {
                    println!("frames in {} (open {} in ParaView)", out_dir.display(), series.display());
                    println!("next: coil render {} (pictures of the surface and a movie)", out_dir.display());
                    if is_round_jet(out_dir) {
                        println!(
                            "      coil axis {} (how far the jet buckled, and whether it coiled or folded)",
                            out_dir.display()
                        );
                    }
                }
                None => println!("frames in {}", out_dir.display()),
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            match &e {
                RunError::Interrupted(_) => eprintln!("`coil resume {}` continues it", out_dir.display()),
                // Advice to resume needs a frame to resume from and a dt to halve.
                RunError::Unstable(i, summary) if summary.frames > 0 && i.dt_s > 0.0 => {
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
pub fn bench_command(options: &BenchOptions, out: &Path) -> Result<(), String> {
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
    chart(&report).save(&out.join("bench.png"))?;
    println!("{text}");
    println!("report in {}", out.display());
    Ok(())
}

/// `coil tradeoff`: runs the sweeps and writes the table and the plot, of the trials measured
/// before a failure where one ended the sweep.
pub fn tradeoff_command(quick: bool, repeats: usize, out: &Path) -> Result<(), String> {
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
    chart(&measured).save(&out.join("tradeoff.png"))?;
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

pub fn list_scenes(dir: &Path) -> Result<ExitCode, String> {
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
                    println!("  {:<30} {}\n  {:<30} coil run {} --variant {}", v.name, v.description, "", path.display(), v.name);
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
pub fn preview(
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
    // In a run's folder the frame is checked against the run's domain as well.
    let log = file.parent().map(|dir| dir.join(LOG)).filter(|log| log.is_file());
    let frame = match log {
        Some(log) => read_run_frame(&file, &Scene::load(&log).map_err(|e| e.to_string())?)?,
        None => read_frame(&file)?,
    };
    let image = render_frame(&frame, view, coloring, range, size).map_err(|e| format!("{}: {e}", file.display()))?;
    let png = output.unwrap_or_else(|| file.with_extension("png"));
    image.save(&png).map_err(|e| format!("{}: cannot be written: {e}", png.display()))?;
    Ok(png)
}
