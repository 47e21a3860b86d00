//! Ctrl-C (SIGINT) or SIGTERM during `coil run`: the run stops after the step it is in, logs
//! itself as "interrupted" with its summary, and keeps every frame it wrote. A second signal
//! ends the process at once, as if nothing had been installed. A closed pipe on stdout
//! (`coil scenes | head`) ends the process quietly, as it does any Unix filter.

use std::sync::atomic::AtomicBool;
#[cfg(unix)]
use std::sync::atomic::Ordering;

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Turns SIGINT and SIGTERM into a request to stop (on Unix; elsewhere they end the process as
/// before): the flag returned, for `RunOptions::stop`.
pub fn watch() -> &'static AtomicBool {
    #[cfg(unix)]
    {
        extern "C" fn on_signal(signal: libc::c_int) {
            REQUESTED.store(true, Ordering::Relaxed);
            // SAFETY: signal() is async-signal-safe; restoring the default makes a second
            // signal end the process.
            unsafe { libc::signal(signal, libc::SIG_DFL) };
        }
        for signal in [libc::SIGINT, libc::SIGTERM] {
            // SAFETY: the handler only stores to an atomic and calls signal().
            unsafe { libc::signal(signal, on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t) };
        }
    }
    &REQUESTED
}

/// Restores SIGPIPE's default, which Rust's runtime ignores: otherwise the first `println!`
/// after the reader of a pipe has gone panics ("failed printing to stdout").
pub fn end_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: called first in main, before any other thread exists; SIG_DFL installs no handler.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
