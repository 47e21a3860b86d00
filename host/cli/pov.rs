//! `coil pov`: a POV-Ray scene beside each frame of a run, rendered with `povray` where it is
//! installed.

use super::surface::frames_of;
use coil::output::pov::PovStage;
use coil::output::preview::speeds;
use coil::output::vtu_read::{read_run_frame, FrameData};
use coil::output::write_atomically;
use coil::run::folder::LOG;
use coil::scene::Scene;
use rayon::prelude::*;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

#[derive(Debug, Clone, Copy)]
pub struct PovOptions {
    /// Render each scene with `povray` (when it is on the PATH) to width x height pixels.
    pub render: Option<(u32, u32)>,
    /// Colour by viscosity (else speed).
    pub by_viscosity: Option<bool>,
}

/// Writes `frame_NNNNNN.pov` beside each frame `path` names, and renders each to
/// `frame_NNNNNN.pov.png` where asked and `povray` is installed.
pub fn pov_command(path: &Path, options: &PovOptions) -> Result<(), String> {
    let (dir, files) = frames_of(path)?;
    let scene = Scene::load_with(&dir.join(LOG), &[]).map_err(|e| e.to_string())?;
    let frames = files.par_iter().map(|f| read_run_frame(f, &scene)).collect::<Result<Vec<FrameData>, String>>()?;
    let viscosity = &scene.material.viscosity;
    let by_viscosity = options.by_viscosity.unwrap_or(viscosity.nu_inf() < viscosity.nu0_m2_s);
    let values: Vec<Vec<f32>> = frames
        .iter()
        .map(|f| if by_viscosity { f.scalars.get("viscosity").cloned() } else { f.vectors.get("velocity").map(|v| speeds(v)) })
        .collect::<Option<_>>()
        .ok_or("the frames hold no viscosity or velocity array")?;
    let range = if by_viscosity {
        (viscosity.nu_inf(), viscosity.nu0_m2_s)
    } else {
        (0.0, f64::from(values.iter().flatten().copied().fold(0.0f32, f32::max)).max(1e-9))
    };
    // One camera for the run: the box the particles reach over all its frames, above its floor.
    let (mut min_m, mut max_m) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in frames.iter().flat_map(|f| &f.position) {
        for a in 0..3 {
            min_m[a] = min_m[a].min(p[a]);
            max_m[a] = max_m[a].max(p[a]);
        }
    }
    if min_m[0] > max_m[0] {
        (min_m, max_m) = (scene.domain.min_m, scene.domain.max_m);
    }
    let spacing = scene.material.particle_spacing_m;
    let plate = super::render::floor_m(&scene);
    let margin = 0.15 * (0..3).map(|a| max_m[a] - min_m[a]).fold(0.0, f64::max);
    for a in [0, 2] {
        min_m[a] -= margin;
        max_m[a] += margin;
    }
    if let Some(top) = plate {
        min_m[1] = top;
    }
    let stage = PovStage { min_m, max_m, plate: plate.map(|top| (top, 2.0 * spacing)), radius_m: scene.support_radius(), range };
    let times = super::render::frame_times(&dir, &scene, &files)?;
    files.par_iter().zip(&frames).zip(&values).zip(&times).try_for_each(|(((file, frame), value), &t)| {
        let pov = file.with_extension("pov");
        write_atomically(&pov, stage.scene(&frame.position, value, t).as_bytes())
            .map_err(|e| format!("{}: cannot be written: {e}", pov.display()))
    })?;
    println!(
        "{} POV-Ray scenes beside the frames in {} (blob components of radius h = {} m, coloured by {} from {} to {})",
        files.len(),
        dir.display(),
        scene.support_radius(),
        if by_viscosity { "viscosity (m^2/s)" } else { "speed (m/s)" },
        range.0,
        range.1
    );
    let Some((width, height)) = options.render else { return Ok(()) };
    let started = Instant::now();
    for file in &files {
        let pov = file.with_extension("pov");
        let png = file.with_extension("pov.png");
        let output = Command::new("povray")
            .args([format!("+I{}", pov.display()), format!("+O{}", png.display())])
            .args([format!("+W{width}"), format!("+H{height}"), "-D".into(), "+A0.3".into(), "+FN".into()])
            .output();
        match output {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                println!("povray is not installed (Debian: apt install povray): the scenes are written, not rendered");
                return Ok(());
            }
            Err(e) => return Err(format!("povray: {e}")),
            Ok(o) if !o.status.success() => {
                let log = String::from_utf8_lossy(&o.stderr);
                let tail: Vec<&str> = log.lines().rev().take(8).collect();
                return Err(format!(
                    "{}: povray failed: {}",
                    pov.display(),
                    tail.into_iter().rev().collect::<Vec<_>>().join("\n")
                ));
            }
            Ok(_) => {}
        }
    }
    let wall = started.elapsed().as_secs_f64();
    println!(
        "rendered with povray to frame_NNNNNN.pov.png, {width} x {height}: {wall:.1} s, {:.1} s a frame",
        wall / files.len().max(1) as f64
    );
    Ok(())
}
