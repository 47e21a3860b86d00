//! Ctrl-C (SIGINT) or SIGTERM during `coil run`: the run stops after the step it is in, logs
//! itself as "interrupted" with its summary, and keeps every frame it wrote. A second signal
//! ends the process at once, as if nothing had been installed. A closed pipe on stdout
//! (`coil scenes | head`) ends the process quietly, as it does any Unix filter.

use std::sync::atomic::AtomicBool;

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Turns SIGINT and SIGTERM into a request to stop (on Unix; elsewhere they end the process as
/// before): the flag returned, for `RunOptions::stop`. A signal that finds the flag already
/// set takes its default action, ending the process.
pub fn watch() -> &'static AtomicBool {
    #[cfg(unix)]
    {
        static INSTALLED: std::sync::Once = std::sync::Once::new();
        INSTALLED.call_once(|| {
            for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
                // In this order: the second signal sees the flag the first one set.
                let installed = signal_hook::flag::register_conditional_default(signal, &REQUESTED)
                    .and_then(|_| signal_hook::flag::register(signal, &REQUESTED));
                if let Err(e) = installed {
                    eprintln!("warning: Ctrl-C will end the run without a checkpoint ({e})");
                }
            }
        });
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
