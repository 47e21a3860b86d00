//! Frames: one VTK XML `.vtu` per frame plus a `.pvd` series that ParaView opens.

pub mod font;
pub mod frame;
pub mod image;
pub mod plot;
pub mod preview;
pub mod render;
pub mod surface;

pub mod points;
pub mod pov;
pub mod vtu;
pub mod vtu_read;

use std::io;
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` through a temporary name and a rename, so a killed run never
/// leaves a torn file.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let written = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if written.is_err() {
        // A full disk leaves a partial temporary; it must not outlive the failure.
        let _ = std::fs::remove_file(&tmp);
    }
    written
}
