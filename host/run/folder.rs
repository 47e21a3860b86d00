//! The files a run writes into its output folder, named here and nowhere else.

use std::io;
use std::path::{Path, PathBuf};

/// The run log (`run::run_log`).
pub const LOG: &str = "run.json";
/// The checkpoint (`run::checkpoint`).
pub const CHECKPOINT: &str = "checkpoint.bin";
/// The wall particles, written once.
pub const BOUNDARY: &str = "boundary.vtu";
/// The movie `coil render` makes of a run's frames.
pub const MOVIE: &str = "render.gif";
/// The same movie as H.264 video, where `ffmpeg` is installed.
pub const MOVIE_MP4: &str = "render.mp4";

/// Held (an advisory file lock) by the run writing into the folder, so that no two share it.
pub const LOCK: &str = "run.lock";

/// Takes output folder `dir` for this process until the returned file is dropped; `Ok(None)`
/// where another process holds it.
pub fn lock(dir: &Path) -> io::Result<Option<std::fs::File>> {
    let file = std::fs::OpenOptions::new().create(true).truncate(false).write(true).open(dir.join(LOCK))?;
    match file.try_lock() {
        Ok(()) => Ok(Some(file)),
        Err(std::fs::TryLockError::WouldBlock) => Ok(None),
        Err(std::fs::TryLockError::Error(e)) => Err(e),
    }
}

/// Frame `k`'s `.vtu` file name; its other formats take the same stem.
pub fn frame_name(k: usize) -> String {
    format!("frame_{k:06}.vtu")
}

/// The `.pvd` series of a run of scene `scene_name` in output folder `dir`.
pub fn series_path(dir: &Path, scene_name: &str) -> PathBuf {
    dir.join(format!("{scene_name}.pvd"))
}

/// The files a run writes into its output folder that `dir` already holds: its log, the
/// boundary, the series, its checkpoint, and every frame in each format, with any temporary
/// left by a killed run; and what `coil surface`, `coil render` and `coil pov` wrote from its
/// frames, which would show the earlier run. Other files are the user's and are never listed.
pub fn earlier_run_files(dir: &Path) -> io::Result<Vec<PathBuf>> {
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        let Some(name) = path.file_name().and_then(|n| n.to_str()) else { continue };
        let name = name.strip_suffix(".tmp").unwrap_or(name);
        let frame = name.strip_prefix("frame_").and_then(|rest| rest.split_once('.')).is_some_and(|(number, ext)| {
            number.len() == 6
                && number.bytes().all(|b| b.is_ascii_digit())
                && ["vtu", "ply", "xyz", "png", "surface.ply", "surface.obj", "render.png", "pov", "pov.png"].contains(&ext)
        });
        if path.is_file() && (frame || [LOG, BOUNDARY, CHECKPOINT, MOVIE, MOVIE_MP4].contains(&name) || name.ends_with(".pvd")) {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}
