//! Frames: one VTK XML `.vtu` per frame plus a `.pvd` series that ParaView opens.

pub mod frame;
pub mod image;
pub mod plot;
pub mod preview;

pub mod points;
pub mod vtu;
pub mod vtu_read;

use std::io;
use std::path::{Path, PathBuf};

/// The files a run writes into its output folder that `dir` already holds: its log, the
/// boundary, the series, its checkpoint, and every frame in each format, with any temporary
/// left by a killed run. Other files are the user's and are never listed.
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
            number.len() == 6 && number.bytes().all(|b| b.is_ascii_digit()) && ["vtu", "ply", "xyz", "png"].contains(&ext)
        });
        if path.is_file()
            && (frame
                || ["run.json", "boundary.vtu", crate::run::checkpoint::FILE_NAME].contains(&name)
                || name.ends_with(".pvd"))
        {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// Writes `bytes` to `path` through a temporary name and a rename, so a killed run never
/// leaves a torn file.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path)
}
