//! Reading the files coil is handed (scenes, run logs, checkpoints, series and frames): regular
//! files only, and never more bytes than the file held when it was opened or than its kind may
//! hold. A link to `/dev/zero` would otherwise be read until memory runs out, and a FIFO would
//! block the reader forever.

use std::io::{Error, Read};
use std::path::Path;

/// The bytes of the regular file `path`, if it holds at most `limit` bytes. A device, FIFO,
/// socket or folder is refused without being opened for reading (so without blocking), and a
/// file longer than `limit` without being read.
pub fn read(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let not_regular = || Error::other("not a regular file (a device, a FIFO or a folder); only regular files are read");
    if !std::fs::metadata(path)?.is_file() {
        return Err(not_regular());
    }
    let file = open_without_blocking(path)?;
    // The path may have been swapped since it was looked at: the open file is what counts.
    let metadata = file.metadata()?;
    if !metadata.is_file() {
        return Err(not_regular());
    }
    let length = metadata.len();
    if length > limit {
        return Err(Error::other(format!("{length} bytes, longer than {limit} bytes, the most read")));
    }
    let mut bytes = Vec::with_capacity(usize::try_from(length).map_err(Error::other)?);
    file.take(length).read_to_end(&mut bytes)?;
    if bytes.len() as u64 != length {
        return Err(Error::other(format!("cut short while it was read ({} of {length} bytes)", bytes.len())));
    }
    Ok(bytes)
}

/// [`read`] as UTF-8 text.
pub fn read_text(path: &Path, limit: u64) -> std::io::Result<String> {
    String::from_utf8(read(path, limit)?).map_err(|_| Error::other("not UTF-8 text"))
}

#[cfg(unix)]
fn open_without_blocking(path: &Path) -> std::io::Result<std::fs::File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new().read(true).custom_flags(libc::O_NONBLOCK).open(path)
}

#[cfg(not(unix))]
fn open_without_blocking(path: &Path) -> std::io::Result<std::fs::File> {
    std::fs::File::open(path)
}
