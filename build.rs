//! With the `cuda` feature, compiles the `kernels` crate to PTX with the `nvptx64-nvidia-cuda`
//! target of the dated nightly toolchain that `kernels/nvptx-toolchain` names (the kernels call
//! NVPTX intrinsics by name, which a later nightly may rename) and leaves it in
//! `OUT_DIR/coil_kernels.ptx`, which `host/cuda/gpu.rs` embeds. A default build needs neither
//! nightly nor CUDA.
//!
//! `COIL_PTX_TARGET_CPU` picks the PTX target (default `sm_70`; the driver JIT-compiles it for
//! newer GPUs).

use std::env;
use std::path::{Path, PathBuf};
use std::process::{exit, Command};

/// The nightly toolchain the kernels are compiled with, as `kernels/nvptx-toolchain` names it.
fn toolchain() -> &'static str {
    include_str!("kernels/nvptx-toolchain").trim()
}

/// The command that installs it.
fn install() -> String {
    format!("rustup toolchain install {} --profile minimal --component rust-src", toolchain())
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var_os("CARGO_FEATURE_CUDA").is_none() {
        return;
    }
    println!("cargo:rerun-if-changed=kernels");
    println!("cargo:rerun-if-env-changed=COIL_PTX_TARGET_CPU");
    let root = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let target_cpu = env::var("COIL_PTX_TARGET_CPU").unwrap_or_else(|_| "sm_70".into());
    require_nightly_with_rust_src();

    // A target folder of its own: the outer build holds the lock on `target/`.
    let target_dir = out.join("ptx-build");
    let mut cargo = Command::new("rustup");
    cargo
        .args(["run", toolchain(), "cargo", "rustc", "-p", "coil-kernels", "--profile", "ptx"])
        .args(["--target", "nvptx64-nvidia-cuda", "-Zbuild-std=core", "--crate-type", "cdylib"])
        .arg("--manifest-path")
        .arg(root.join("Cargo.toml"))
        .arg("--target-dir")
        .arg(&target_dir)
        .args(["--", "-C", &format!("target-cpu={target_cpu}"), "--emit=asm", "-C", "linker=true"]);
    // The outer cargo's settings for this build script would steer the nested one to the host
    // compiler and flags.
    for (key, _) in env::vars_os() {
        let key = key.to_string_lossy();
        let keep = key == "CARGO_HOME"
            || key.starts_with("CARGO_NET")
            || key.starts_with("CARGO_HTTP")
            || key.starts_with("CARGO_REGISTR");
        let steers = key.starts_with("CARGO_")
            || key.starts_with("RUSTC")
            || matches!(
                &*key,
                "RUSTFLAGS"
                    | "RUSTDOCFLAGS"
                    | "RUSTUP_TOOLCHAIN"
                    | "TARGET"
                    | "HOST"
                    | "PROFILE"
                    | "OUT_DIR"
                    | "OPT_LEVEL"
                    | "DEBUG"
                    | "NUM_JOBS"
            );
        if steers && !keep {
            cargo.env_remove(&*key);
        }
    }
    let status = cargo.status().unwrap_or_else(|e| fail(&format!("cannot start `rustup run {} cargo`: {e}", toolchain())));
    if !status.success() {
        fail("compiling the kernels to PTX failed (see the errors above)");
    }
    let ptx = target_dir.join("nvptx64-nvidia-cuda/ptx/deps/coil_kernels.s");
    copy(&ptx, &out.join("coil_kernels.ptx"));
}

fn require_nightly_with_rust_src() {
    let installed = Command::new("rustup")
        .arg(format!("+{}", toolchain()))
        .args(["component", "list", "--installed"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).lines().any(|l| l.starts_with("rust-src")));
    match installed {
        Some(true) => {}
        Some(false) => fail(&format!("the `cuda` feature needs rust-src for {}; install it with: {}", toolchain(), install())),
        None => fail(&format!("the `cuda` feature compiles the kernels with {}; install it with: {}", toolchain(), install())),
    }
}

fn copy(from: &Path, to: &Path) {
    if let Err(e) = std::fs::copy(from, to) {
        fail(&format!("the PTX compiler left no {}: {e}", from.display()));
    }
}

fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    println!("cargo:warning={message}");
    exit(1);
}
