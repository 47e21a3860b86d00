//! `coil surface`: the free-surface mesh of each frame of a run, written beside the frame.

use coil::output::surface::{mesh_path, reconstruct, Fluid, MeshFormat, SurfaceParameters};
use coil::output::vtu_read::{read_run_frame, read_series};
use coil::output::write_atomically;
use coil::run::folder::{series_path, LOG};
use coil::scene::Scene;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The knobs of `coil surface`, relative to the run's spacing and h.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceOptions {
    /// Marching-cubes edge in particle spacings.
    pub cube_size: f64,
    /// The density kernel's support in the run's h.
    pub support_radius: f64,
    /// Iso-surface at this fraction of rho0.
    pub iso_threshold: f64,
    pub formats: &'static [MeshFormat],
    pub quiet: bool,
}

/// The run folder `path` is in, or is, and the frames it names: every frame of the series, or
/// the one `.vtu` given.
pub fn frames_of(path: &Path) -> Result<(PathBuf, Vec<PathBuf>), String> {
    if path.is_dir() {
        let log = path.join(LOG);
        let scene = Scene::load_with(&log, &[]).map_err(|e| e.to_string())?;
        let series = read_series(&series_path(path, &scene.name))?;
        return Ok((path.to_path_buf(), series.into_iter().map(|(_, file)| path.join(file)).collect()));
    }
    if path.extension().and_then(|e| e.to_str()) != Some("vtu") {
        return Err(format!("{}: neither a run's output folder nor a .vtu frame", path.display()));
    }
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    Ok((dir.to_path_buf(), vec![path.to_path_buf()]))
}

/// Meshes the frames `path` names, in parallel, and writes each beside its frame; prints the
/// meshes written and the time per frame.
pub fn surface_command(path: &Path, options: &SurfaceOptions) -> Result<(), String> {
    let checks = [
        ("--cube-size", options.cube_size, 0.05, 4.0),
        ("--support-radius", options.support_radius, 0.5, 4.0),
        ("--iso", options.iso_threshold, 0.01, 2.0),
    ];
    for (name, value, lo, hi) in checks {
        if !(lo..=hi).contains(&value) {
            return Err(format!("{name}: must be from {lo} to {hi}, got {value}"));
        }
    }
    let (dir, frames) = frames_of(path)?;
    let log = dir.join(LOG);
    let scene = Scene::load_with(&log, &[]).map_err(|e| e.to_string())?;
    let spacing = scene.material.particle_spacing_m;
    let mut parameters = SurfaceParameters::of_scene(&scene);
    parameters.cube_size_m = options.cube_size * spacing;
    parameters.support_radius_m = options.support_radius * scene.support_radius();
    parameters.iso_threshold = options.iso_threshold;
    let bar = if options.quiet { ProgressBar::hidden() } else { ProgressBar::new(frames.len() as u64) };
    bar.set_style(
        ProgressStyle::with_template("{bar:30.cyan/blue} {pos}/{len} frames meshed, ETA {eta}").expect("a valid template"),
    );
    let started = Instant::now();
    let triangles = frames
        .par_iter()
        .map(|frame_file| {
            let frame = read_run_frame(frame_file, &scene)?;
            let mesh = Fluid::of(&frame)
                .and_then(|fluid| reconstruct(fluid, &parameters))
                .map_err(|e| format!("{}: {e}", frame_file.display()))?;
            for &format in options.formats {
                let out = mesh_path(frame_file, format);
                let bytes = match format {
                    MeshFormat::Ply => mesh.to_ply(),
                    MeshFormat::Obj => mesh.to_obj(),
                };
                write_atomically(&out, &bytes).map_err(|e| format!("{}: cannot be written: {e}", out.display()))?;
            }
            bar.inc(1);
            Ok(mesh.triangles.len())
        })
        .collect::<Result<Vec<usize>, String>>()?;
    bar.finish_and_clear();
    let wall = started.elapsed().as_secs_f64();
    let mean = triangles.iter().sum::<usize>() as f64 / triangles.len().max(1) as f64;
    let formats: Vec<&str> = options.formats.iter().map(|f| f.extension()).collect();
    println!(
        "{} surface meshes ({}) beside the frames in {}: {mean:.0} triangles a frame on average; {wall:.1} s on {} threads, {:.2} s of a thread a frame (cubes {} m, support {} m, iso {} rho0)",
        triangles.len(),
        formats.join(", "),
        dir.display(),
        rayon::current_num_threads(),
        wall / triangles.len().max(1) as f64 * rayon::current_num_threads() as f64,
        parameters.cube_size_m,
        parameters.support_radius_m,
        parameters.iso_threshold
    );
    Ok(())
}
