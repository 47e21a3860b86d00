//! `coil render`: pictures of a run's free surface from fixed cameras, one PNG beside each frame,
//! and for a whole run an animated GIF of them, and an MP4 where `ffmpeg` is installed.

use super::surface::frames_of;
use coil::output::render::{Camera, Stage};
use coil::output::surface::{reconstruct, Fluid, SurfaceMesh, SurfaceParameters};
use coil::output::vtu_read::{read_run_frame, read_series};
use coil::output::write_atomically;
use coil::run::folder::{series_path, LOG, MOVIE, MOVIE_MP4};
use coil::scene::{Boundary, Scene};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// What the colours show.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RenderColor {
    /// Viscosity for a Cross fluid (nu_inf to nu0, as the paper's figures), speed otherwise.
    Auto,
    Viscosity,
    Speed,
}

#[derive(Debug, Clone)]
pub struct RenderOptions {
    pub cameras: Vec<Camera>,
    pub color: RenderColor,
    pub range: Option<(f64, f64)>,
    /// Pixels per panel side.
    pub size: usize,
    /// Hundredths of a second each picture shows in the movie.
    pub movie_delay_cs: u16,
    pub quiet: bool,
}

/// The box the cameras frame: what the fluid's surface reaches over all `meshes`, a tenth wider
/// each way, above the floor of the scene's first boundary (a plate's top or a box's floor),
/// drawn across it.
fn stage_of(scene: &Scene, meshes: &[SurfaceMesh], quantity: String, range: (f64, f64), size: usize) -> Stage {
    let (mut min_m, mut max_m) = (scene.domain.max_m, scene.domain.min_m);
    for v in meshes.iter().flat_map(|m| &m.vertices) {
        for a in 0..3 {
            min_m[a] = min_m[a].min(f64::from(v[a]));
            max_m[a] = max_m[a].max(f64::from(v[a]));
        }
    }
    if (0..3).any(|a| min_m[a] > max_m[a]) {
        (min_m, max_m) = (scene.domain.min_m, scene.domain.max_m);
    }
    let margin = (0..3).map(|a| max_m[a] - min_m[a]).fold(0.0, f64::max) * 0.1;
    for a in [0, 2] {
        min_m[a] -= margin;
        max_m[a] += margin;
    }
    let spacing = scene.material.particle_spacing_m;
    let plate = floor_m(scene);
    if let Some(top) = plate {
        min_m[1] = top - 2.0 * spacing;
    }
    Stage { min_m, max_m, plate: plate.map(|top| (top, 2.0 * spacing)), quantity, range, size }
}

/// The floor the pictures stand on (m): the top of the scene's first boundary, a plate, or a
/// box's floor.
pub fn floor_m(scene: &Scene) -> Option<f64> {
    scene.boundaries.first().map(|b| match *b {
        Boundary::Plate { height_m, .. } => height_m,
        Boundary::Box { min_m, .. } => min_m[1],
    })
}

/// Renders the frames `path` names; for a run's folder also writes `render.gif`. Prints where.
pub fn render_command(path: &Path, options: &RenderOptions) -> Result<(), String> {
    if !(64..=4096).contains(&options.size) {
        return Err(format!("--size: must be 64 to 4096 pixels, got {}", options.size));
    }
    let (dir, frames) = frames_of(path)?;
    let log = dir.join(LOG);
    let scene = Scene::load_with(&log, &[]).map_err(|e| e.to_string())?;
    let times = frame_times(&dir, &scene, &frames)?;
    let viscosity = &scene.material.viscosity;
    let by_viscosity = match options.color {
        RenderColor::Auto => viscosity.nu_inf() < viscosity.nu0_m2_s,
        RenderColor::Viscosity => true,
        RenderColor::Speed => false,
    };
    let parameters = SurfaceParameters::of_scene(&scene);
    let bar = if options.quiet { ProgressBar::hidden() } else { ProgressBar::new(2 * frames.len() as u64) };
    bar.set_style(
        ProgressStyle::with_template("{bar:30.cyan/blue} {pos}/{len} (mesh, then draw), ETA {eta}").expect("a valid template"),
    );
    let started = Instant::now();
    let meshes = frames
        .par_iter()
        .map(|file| {
            let frame = read_run_frame(file, &scene)?;
            let mesh = Fluid::of(&frame)
                .and_then(|fluid| reconstruct(fluid, &parameters))
                .map_err(|e| format!("{}: {e}", file.display()))?;
            bar.inc(1);
            Ok(mesh)
        })
        .collect::<Result<Vec<SurfaceMesh>, String>>()?;
    let field = |m: &SurfaceMesh| if by_viscosity { m.viscosity.clone() } else { m.speed.clone() };
    // One range for every frame, so colours compare across the movie.
    let range = options.range.unwrap_or_else(|| {
        if by_viscosity {
            (viscosity.nu_inf(), viscosity.nu0_m2_s)
        } else {
            let top = meshes.iter().flat_map(|m| m.speed.iter().copied()).fold(0.0f32, f32::max);
            (0.0, f64::from(top).max(1e-9))
        }
    });
    let quantity = if by_viscosity { "viscosity nu (m^2/s)" } else { "speed |v| (m/s)" };
    let stage = stage_of(&scene, &meshes, quantity.into(), range, options.size);
    let pictures = frames
        .par_iter()
        .zip(&meshes)
        .zip(&times)
        .map(|((file, mesh), &t)| {
            let image = stage.render(mesh, &field(mesh), t, &options.cameras);
            let png = file.with_extension("render.png");
            image.save(&png).map_err(|e| format!("{}: cannot be written: {e}", png.display()))?;
            bar.inc(1);
            Ok((png, image))
        })
        .collect::<Result<Vec<_>, String>>()?;
    bar.finish_and_clear();
    let drawn = started.elapsed().as_secs_f64();
    let movie = if path.is_dir() && !pictures.is_empty() {
        let gif = write_movie(&dir, &pictures, options.movie_delay_cs)?;
        Some((gif, write_mp4(&dir, &pictures, options.movie_delay_cs)))
    } else {
        None
    };
    let first = pictures.first().map(|(p, _)| p.display().to_string()).unwrap_or_default();
    println!(
        "{} pictures ({} views, {} px a panel, coloured by {quantity} from {} to {}) beside the frames, e.g. {first}; {drawn:.1} s on {} threads",
        pictures.len(),
        options.cameras.len(),
        options.size,
        range.0,
        range.1,
        rayon::current_num_threads()
    );
    if let Some((gif, mp4)) = movie {
        let seconds = started.elapsed().as_secs_f64() - drawn;
        match mp4 {
            Mp4::Written(mp4) => println!("movie: {} and {} ({seconds:.1} s)", gif.display(), mp4.display()),
            Mp4::NoFfmpeg => println!(
                "movie: {} ({seconds:.1} s); for {MOVIE_MP4} as well, install ffmpeg (Debian: apt install ffmpeg)",
                gif.display()
            ),
            Mp4::Failed(why) => {
                println!("movie: {} ({seconds:.1} s)", gif.display());
                eprintln!("warning: {why}");
            }
        }
    }
    Ok(())
}

/// Each frame's simulated time (s): from the run's series where it lists the frame, else 0.
pub fn frame_times(dir: &Path, scene: &Scene, frames: &[PathBuf]) -> Result<Vec<f64>, String> {
    let series = read_series(&series_path(dir, &scene.name)).unwrap_or_default();
    Ok(frames
        .iter()
        .map(|f| {
            let name = f.file_name().and_then(|n| n.to_str()).unwrap_or_default();
            series.iter().find(|(_, file)| file == name).map_or(0.0, |(t, _)| *t)
        })
        .collect())
}

/// The pictures, at least one, as an animated GIF, `render.gif` in `dir`, looping.
fn write_movie(dir: &Path, pictures: &[(PathBuf, coil::output::image::Image)], delay_cs: u16) -> Result<PathBuf, String> {
    let path = dir.join(MOVIE);
    let Some((_, first)) = pictures.first() else { return Err(format!("{}: no pictures to make it of", path.display())) };
    let (w, h) = (u16::try_from(first.width), u16::try_from(first.height));
    let (Ok(w), Ok(h)) = (w, h) else { return Err("--size: the pictures are too large for a GIF".into()) };
    let frames: Vec<gif::Frame> = pictures
        .par_iter()
        .map(|(_, image)| {
            let mut frame = gif::Frame::from_rgb_speed(w, h, &image.pixels, 10);
            frame.delay = delay_cs;
            frame
        })
        .collect();
    let mut bytes = Vec::new();
    {
        let mut encoder = gif::Encoder::new(&mut bytes, w, h, &[]).map_err(|e| format!("{}: {e}", path.display()))?;
        encoder.set_repeat(gif::Repeat::Infinite).map_err(|e| format!("{}: {e}", path.display()))?;
        for frame in &frames {
            encoder.write_frame(frame).map_err(|e| format!("{}: {e}", path.display()))?;
        }
    }
    write_atomically(&path, &bytes).map_err(|e| format!("{}: cannot be written: {e}", path.display()))?;
    Ok(path)
}

/// What became of the MP4.
enum Mp4 {
    Written(PathBuf),
    /// No `ffmpeg` on the PATH.
    NoFfmpeg,
    /// Why ffmpeg wrote none; the GIF and the pictures stand.
    Failed(String),
}

/// The pictures as H.264 video (yuv420p, sizes padded to even, as players want), `render.mp4` in
/// `dir`, through `ffmpeg` fed the raw pictures on its input: written under a temporary name and
/// renamed when ffmpeg succeeds, so a failed encode leaves nothing.
fn write_mp4(dir: &Path, pictures: &[(PathBuf, coil::output::image::Image)], delay_cs: u16) -> Mp4 {
    let path = dir.join(MOVIE_MP4);
    let partial = dir.join(format!("{MOVIE_MP4}.tmp"));
    let Some((_, first)) = pictures.first() else { return Mp4::Failed(format!("{}: no pictures", path.display())) };
    let size = format!("{}x{}", first.width, first.height);
    let rate = format!("100/{}", delay_cs.max(1));
    let args = ["-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", &size, "-framerate", &rate, "-i", "-"];
    let encode = ["-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "20", "-f", "mp4"];
    let spawned = Command::new("ffmpeg")
        .args(args)
        .args(encode)
        .arg(&partial)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn();
    let mut child = match spawned {
        Ok(child) => child,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Mp4::NoFfmpeg,
        Err(e) => return Mp4::Failed(format!("{}: ffmpeg could not be started: {e}", path.display())),
    };
    let fed = child.stdin.take().map_or(Ok(()), |mut input| pictures.iter().try_for_each(|(_, p)| input.write_all(&p.pixels)));
    let failed = |why: String| {
        std::fs::remove_file(&partial).ok();
        Mp4::Failed(format!("{} not written: {why}", path.display()))
    };
    let finished = match child.wait_with_output() {
        Ok(finished) => finished,
        Err(e) => return failed(format!("ffmpeg: {e}")),
    };
    if !finished.status.success() {
        let said = String::from_utf8_lossy(&finished.stderr);
        return failed(format!("ffmpeg {}: {}", finished.status, said.trim().lines().last().unwrap_or("no message")));
    }
    if let Err(e) = fed {
        return failed(format!("ffmpeg stopped reading the pictures: {e}"));
    }
    match std::fs::rename(&partial, &path) {
        Ok(()) => Mp4::Written(path),
        Err(e) => failed(format!("{e}")),
    }
}
